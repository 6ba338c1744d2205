#pragma once
// Skotheim et al. 2012's Table I reproduced through the whole product: simulate K cells' captures
// and N seat placements (drawn as in the paper: +-100 mm in x and y, +-25 deg tilt, +-180 deg
// yaw), calibrate each cell's camera, laser plane and handling_base <- sensor from its own
// captures (capture_calibration.hpp; never the truth), localize every seat through one
// localize::JobRunner per cell, and compare the hole grasp with the truth in handling_base: after
// PPF (the coarse pose) and after ICP, the share within the gripper's +-10 mm, the reported
// uncertainty against the error (1-sigma coverage, 3-sigma exceedances), and the time per part.
//
// A cell whose calibration is refused (the calibration's own checks: a lens model that does not
// invert, a laser plane that does not converge, ...) is listed with the reason and localizes
// nothing, as a real cell would stop and be recalibrated. Units mm, ms.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "core/progress.hpp"

namespace lasercell::datasets {

struct Table1Options {
  int placements = 1000;  ///< Seat placements in all, split evenly between the cells.
  int cells = 1;          ///< Independent simulated cells (seeds seed, seed + 1, ...).
  std::uint64_t seed = 1;
  int threads = 1;                  ///< Localization threads (0 = all cores).
  std::string work_dir = "table1";  ///< Captures, calibrations and the shared model cache.
  std::string sim_config;           ///< Simulator settings (SIM.yaml); empty: `profile`.
  /// Named simulation profile (sim_profile.hpp) when sim_config is empty: "realistic" (the
  /// default for accuracy benchmarks) or "ideal".
  std::string profile = "realistic";
  /// A localize options file (registration/localize_options_io.hpp) for the seat's job; its
  /// `model:` section (defaults where silent) builds the seat's PPF model. Empty: the job's and
  /// the simulated part file's defaults.
  std::string options_file;
  /// Reuse a cell's captures from an earlier run in work_dir when they were simulated with the
  /// same settings (seed included); the calibration and every localization run again.
  bool reuse_captures = false;

  /// Throws OptionError naming the field (placements and cells positive, placements a
  /// multiple of cells, threads >= 0, a known profile).
  void Check() const;
};

/// Runs the benchmark; the result (`format: lasercell.bench_table1`, version 2) holds every
/// trial, the per-cell calibrations and refusals, and the summary statistics.
nlohmann::json RunTable1Bench(const Table1Options& options, const ProgressCallback& progress = {});

/// The Markdown section for BENCHMARKS.md, every number taken from `result` so that text and
/// table agree.
std::string Table1Markdown(const nlohmann::json& result);

}  // namespace lasercell::datasets
