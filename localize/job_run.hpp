#pragma once
// Running a job (job.hpp): load the cell, camera and part models (PPF models from the cache when
// unchanged), take the next sweep from the job's profile source, triangulate it into the target
// frame through the cell's frame graph (linear axis record or robot joints), and localize the
// parts (localize_parts.hpp). The result file is `lasercell.localization_job`, version 1
// (JobResultJson).
//
// Frames: the sweep and every pose are in the job's target frame (default handling_base): part
// poses `<target>_from_<part>_<k>` and grasp poses `<target>_from_<grasp>` (the handling
// robot's gripper_tcp target). Units mm, rad; timings ms.

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/frame_graph.hpp"
#include "core/progress.hpp"
#include "localize/job.hpp"
#include "localize/localize_parts.hpp"
#include "localize/part_model.hpp"
#include "triangulation/profile_source.hpp"
#include "triangulation/sweep.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::localize {

/// Format name and version of job result files.
inline constexpr const char* kJobResultFormat = "lasercell.localization_job";
inline constexpr int kJobResultFormatVersion = 1;

/// Options of RunJob.
struct JobRunOptions {
  /// Profiles from here instead of the job's source.file (a stream; nullptr = the job's file).
  std::shared_ptr<triangulation::ProfileSource> source;
  bool load_meshes = false;   ///< Keep the parts' meshes (for a report).
  int threads = -1;           ///< Overrides the job's threads when >= 0.
  ProgressCallback progress;  ///< Stages: "models", "profiles", "triangulation", then searches.
};

/// Wall time of the job's stages, ms.
struct JobTimings {
  double setup_ms = 0.0;          ///< Cell, camera, laser plane, lookup tables.
  double models_ms = 0.0;         ///< Part models (built or from the cache).
  double profiles_ms = 0.0;       ///< Reading the sweep from its source.
  double triangulation_ms = 0.0;  ///< Profiles -> points in the target frame.
  double localization_ms = 0.0;   ///< LocalizeParts.
  /// This sweep: triangulation + localization + the job's own work around them.
  double run_ms = 0.0;
  double total_ms = 0.0;  ///< setup + models + profiles + run.
};

/// Everything a job run produced.
struct JobResult {
  Job job;
  std::string source;  ///< The profile source, e.g. "file seat_000.lcp".
  std::string laser_plane_source;
  triangulation::SweepResult sweep;  ///< The sweep in the target frame.
  /// One per job part, in job order (shared by the runs of one JobRunner).
  std::shared_ptr<const std::vector<PartModel>> models;
  LocalizePartsResult parts;
  /// Calibrated edges on the target <- sensor path without a covariance (their uncertainty is
  /// not in the poses' covariances), and other caveats.
  std::vector<std::string> notes;
  JobTimings timings;
  /// One line: instances found / requested, graspable, total time.
  std::string Summary() const;
};

/// A job loaded once (cell, camera, lookup tables, part models) and run on sweep after sweep, as
/// a cell does while profiles arrive.
class JobRunner {
 public:
  /// Loads everything the job needs. Throws as RunJob does for the cell, camera, laser plane,
  /// target frame and models.
  explicit JobRunner(const Job& job, const JobRunOptions& options = {});
  ~JobRunner();
  JobRunner(const JobRunner&) = delete;
  JobRunner& operator=(const JobRunner&) = delete;

  /// Localizes the job's parts in one sweep; `source_name` names it in the result. Timings
  /// setup_ms and models_ms are the runner's (paid once).
  JobResult Run(const triangulation::ProfileSet& profiles, const std::string& source_name);
  /// The next sweep of `source`, or nullopt when it has none.
  std::optional<JobResult> RunNext(triangulation::ProfileSource& source);
  const Job& job() const { return job_; }
  /// The loaded part models, in job order.
  const std::vector<PartModel>& models() const { return *models_; }
  /// The same, shared (the runner's results hold it too).
  std::shared_ptr<const std::vector<PartModel>> shared_models() const { return models_; }

 private:
  Job job_;
  JobRunOptions options_;
  int threads_ = 0;
  FrameGraph cell_;
  triangulation::ScanSetup setup_;
  std::unique_ptr<triangulation::Triangulator> triangulator_;
  std::shared_ptr<const std::vector<PartModel>> models_;
  double setup_ms_ = 0.0, models_ms_ = 0.0;
};

/// Runs `job` once on the next sweep of options.source (default: the job's profile file). Throws
/// FileError / InputError naming the file and what to do for a cell, camera, laser plane, profile
/// file or model that cannot be used, a target frame the cell cannot reach from the sensor, or an
/// ROI that holds no sweep point; outcomes (parts not found, not graspable) are in the result.
JobResult RunJob(const Job& job, const JobRunOptions& options = {});

/// The result file (format lasercell.localization_job, version 1): job, inputs, per instance
/// part, frame, pose (file notation + 4x4 matrix), covariance and 1-sigma, grasps, support, ICP,
/// graspable (+ reason), ambiguous (+ reason); per part what was not found and why; models;
/// notes; per-stage timings.
nlohmann::json JobResultJson(const JobResult& result);

/// One entry of the result file's `searches`: the part, requested and found instances, why fewer
/// were found, the last search's rejected candidates, the work (`counts`: voxel points, reference
/// points, scene pairs, votes) and the stage times summed over the part's searches (`timings_ms`;
/// `judgement` is the grasp fits and explained points after each found instance).
nlohmann::json PartSearchJson(const PartSearch& search);

/// A copy of `cell` with one static edge <target>_from_<part>_<k> per found instance (and its
/// covariance when valid), so `lasercell frames get` answers where a part lies.
FrameGraph CellWithInstances(const FrameGraph& cell, const JobResult& result);

}  // namespace lasercell::localize
