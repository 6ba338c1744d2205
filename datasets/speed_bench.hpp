#pragma once
// `lasercell bench speed`: where the time of a localization goes, stage by stage, with the counts
// that explain it (points per stage, reference points, scene pairs, votes, model entries per
// looked-up key, ns per pair and per vote), on
//   (a) simulated seat sweeps: organized ~320k-point linear sweeps of the chair seat, each
//       triangulated with the simulated sensor's true camera and laser plane in the sensor frame
//       at t0 and localized the way a job localizes (localize::LocalizeParts: ROI, normals along
//       each point's line of sight, the search, the grasp's local fit) with the seat's part file;
//   (b) real unorganized and organized scans: UWA rs1 and rs22 with the parasaurolophus, rs1
//       thinned to every 3rd point (38k) without its normals (a ~40k-point unorganized scan whose
//       normals are estimated), PCL's Stanford bunny view bun0 in bun4 and PCL's milk carton in
//       its Kinect scene, through registration::LocalizeInCloud at its defaults (what
//       `lasercell localize` runs);
//   (c) a sweep-size series: the same seat sweep simulated with more or fewer profiles.
// Every case runs `runs` times per thread count with the model prebuilt and the files parsed
// before the clock starts; the tables give medians. Each case's answer is checked against its
// reference (the simulator's truth; the committed reference poses of rs1, rs22 and milk) so that
// a faster configuration that loses accuracy shows it. Units mm, ms, ns.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.hpp"

namespace lasercell::datasets {

/// Options of RunSpeedBench.
struct SpeedBenchOptions {
  int runs = 10;        ///< Timed runs per case and thread count (median reported), >= 1.
  int placements = 10;  ///< Simulated seat sweeps of case (a), >= 1.
  std::uint64_t seed = 1;
  /// Simulation profile of the seat sweeps (sim_profile.hpp): "realistic" or "ideal".
  std::string profile = "realistic";
  std::string work_dir = "speed";  ///< Simulated sweeps and the model cache.
  /// Source tree holding datasets/real and tests/registration/data (the bundled scans and their
  /// reference poses). Required when `real` is set.
  std::string source_dir;
  /// ../shared/data (UWA rs22 and its part are not bundled); "" leaves rs22 out, said in the
  /// result.
  std::string shared_data_dir;
  std::vector<int> threads = {1, 0};  ///< Thread counts to time (0 = all cores).
  /// Profiles per seat sweep of the size series (c); the default 350 gives ~320k points.
  std::vector<int> series_profiles = {55, 110, 220, 440};
  /// A localize options file (registration/localize_options_io.hpp) for every case; "" = the
  /// defaults. Its `model:` section is not used (the seat's part file and the real models'
  /// defaults build the models).
  std::string options_file;
  bool seat = true;    ///< Run (a).
  bool real = true;    ///< Run (b).
  bool series = true;  ///< Run (c), single thread.

  /// Throws OptionError naming the field.
  void Check() const;
};

/// Runs the benchmark; the result (`format: lasercell.bench_speed`, version 1) holds every case
/// with its per-stage medians, counts and accuracy, and the size series.
nlohmann::json RunSpeedBench(const SpeedBenchOptions& options,
                             const ProgressCallback& progress = {});

/// The Markdown section for BENCHMARKS.md, every number taken from `result`.
std::string SpeedMarkdown(const nlohmann::json& result);

}  // namespace lasercell::datasets
