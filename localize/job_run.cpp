#include "localize/job_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "calib/camera_model.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/json_io.hpp"
#include "core/provenance.hpp"
#include "registration/localization_json.hpp"
#include "triangulation/linear_sweep.hpp"
#include "triangulation/sensor_error_field.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::localize {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

triangulation::SweepOptions SweepOptionsOf(const Job& job, int threads) {
  triangulation::SweepOptions o;
  if (!job.linear_record.empty()) {
    o = triangulation::ReadLinearSweepRecord(job.linear_record).Options();
  } else {
    o.motion = triangulation::SweepMotion::kRobot;
    o.robot = job.robot;
  }
  o.target_frame = job.target_frame;
  o.threads = threads;
  return o;
}

// The covariance of target <- sensor (the calibrated edges that place the sweep) and what it
// leaves out. A robot sweep is evaluated at its middle profile's joints.
TransformWithCovarianceResult PlacementCovariance(const FrameGraph& cell, const Job& job,
                                                  const triangulation::ProfileSet& profiles,
                                                  const triangulation::SweepOptions& sweep,
                                                  std::vector<std::string>* notes) {
  JointValues joints;
  if (sweep.motion == triangulation::SweepMotion::kRobot && !profiles.profiles.empty()) {
    const std::string robot = sweep.robot.empty() ? profiles.header.robot : sweep.robot;
    joints[robot] = profiles.profiles[profiles.profiles.size() / 2].joints_rad;
  }
  const TransformWithCovarianceResult placement =
      cell.TransformWithCovariance(job.target_frame, "sensor", joints);
  for (const std::string& edge : placement.edges_without_covariance) {
    notes->push_back("edge " + edge + " has no covariance: its uncertainty is not in the poses");
  }
  if (placement.crosses_dynamic_edge) {
    notes->push_back("the path " + job.target_frame +
                     " <- sensor passes a robot: joint and kinematic uncertainty are not in the "
                     "pose covariances");
  }
  return placement;
}

// The placement's response to the plane's error modes, when an edge on the path holds one for
// this plane calibration; empty (0 columns) otherwise, with a note when one is stale.
Eigen::Matrix<double, 6, Eigen::Dynamic> PlacementResponse(
    const TransformWithCovarianceResult& placement, const std::string& laser,
    const LaserPlaneEntry& plane, std::vector<std::string>* notes) {
  Eigen::Matrix<double, 6, Eigen::Dynamic> sum;
  for (const SensorModeResponse& r : placement.sensor_responses) {
    if (r.laser != laser) continue;
    const auto modes = static_cast<Eigen::Index>(plane.error_modes.size());
    if (r.plane_digest != plane.provenance.input_digest || r.columns.cols() != modes) {
      notes->push_back("a placement edge's response to laser plane '" + laser +
                       "' was computed for another calibration of it; not used");
      continue;
    }
    sum = sum.cols() == 0 ? r.columns : Eigen::Matrix<double, 6, Eigen::Dynamic>(sum + r.columns);
  }
  return sum;
}

// The laser plane's uncertainty when the plane came from the cell with a covariance; otherwise
// unset, with a note.
std::optional<LaserPlaneUncertainty> PlaneUncertainty(
    const FrameGraph& cell, const Job& job, const triangulation::ScanSetup& setup,
    const triangulation::SweepResult& sweep, const TransformWithCovarianceResult& placement,
    const calib::CameraModel& camera, std::vector<std::string>* notes) {
  const auto it = cell.laser_planes().find(job.laser);
  if (it == cell.laser_planes().end() || !it->second.covariance) {
    notes->push_back("laser plane '" + job.laser +
                     "' has no covariance in the cell: its uncertainty is not in the poses");
    return std::nullopt;
  }
  LaserPlaneUncertainty u;
  u.plane_in_sensor = setup.laser_plane;
  u.covariance = *it->second.covariance;
  u.target_from_sensor = sweep.frame_from_sensor;
  const Eigen::Matrix<double, 6, Eigen::Dynamic> response =
      it->second.error_modes.empty() ? Eigen::Matrix<double, 6, Eigen::Dynamic>()
                                     : PlacementResponse(placement, job.laser, it->second, notes);
  if (response.cols() > 0) {
    // Camera and plane mode by mode, with what each did to the placement calibrated through
    // them: the shared error counted once, with its sign (laser_plane_uncertainty.hpp).
    auto field = std::make_shared<const triangulation::SensorErrorField>(camera, it->second);
    u.mode_displacements = [field](const Eigen::Vector3d& p) { return field->Displacements(p); };
    u.placement_response = response;
    notes->push_back("laser plane '" + job.laser + "': its " + std::to_string(response.cols()) +
                     " error modes (camera and plane) are in the poses' covariance together "
                     "with what they did to the placement");
    return u;
  }
  // The camera's part of the plane's error is shared with the placement calibrated through the
  // same camera and plane, which absorbs most of it; first-order independence would count it
  // as if nothing absorbed it (Table I: 3-6x the hole's actual error along the line of sight).
  if (it->second.camera_covariance) {
    u.covariance -= *it->second.camera_covariance;
    notes->push_back("laser plane '" + job.laser +
                     "': its camera part is not in the poses' covariance (shared with the "
                     "placement calibrated through the same camera)");
  }
  return u;
}

LocalizePartsOptions PartsOptionsOf(const Job& job, int threads) {
  LocalizePartsOptions o;
  o.use_roi = job.use_roi;
  o.roi = job.roi;
  o.support = job.support;
  o.localize = job.settings.localize;
  o.grasp_tolerance_mm = job.grasp_tolerance_mm;
  o.scan_noise_mm = job.scan_noise_mm;
  o.max_rmse_factor = job.max_rmse_factor;
  o.threads = threads;
  return o;
}

nlohmann::json GraspJson(const GraspPose& g, const std::string& target) {
  nlohmann::json j = {{"name", g.name},
                      {target + "_from_grasp", json::Pose(g.target_from_grasp)},
                      {"matrix", json::MatrixRows(g.target_from_grasp)},
                      {"covariance", json::Covariance(g.covariance)},
                      {"position_sigma_mm", g.position_sigma_mm},
                      {"within_tolerance", g.within_tolerance},
                      {"refined_locally", g.refined_locally}};
  if (g.refined_locally || !g.local_note.empty()) {
    j["local_fit"] = {{"points", g.local_points},
                      {"rmse_mm", g.local_rmse_mm},
                      {"shift_mm", g.local_shift_mm},
                      {"note", g.local_note}};
  }
  return j;
}

nlohmann::json InstanceJson(const PartInstance& inst, const std::string& target) {
  nlohmann::json j;
  j["part"] = inst.part;
  j["frame"] = inst.frame;
  j[target + "_from_part"] = json::Pose(inst.target_from_part);
  j["matrix"] = json::MatrixRows(inst.target_from_part);
  j["covariance_valid"] = inst.covariance_valid;
  j["covariance"] = inst.covariance_valid ? json::Covariance(inst.covariance) : nlohmann::json();
  j["covariance_terms"] = {{"icp", json::Covariance(inst.covariance_terms.icp)},
                           {"placement", json::Covariance(inst.covariance_terms.placement)},
                           {"laser_plane", json::Covariance(inst.covariance_terms.laser_plane)}};
  j["grasps"] = nlohmann::json::array();
  for (const GraspPose& g : inst.grasps) j["grasps"].push_back(GraspJson(g, target));
  j["graspable"] = inst.graspable;
  if (!inst.graspable) j["not_graspable_reason"] = inst.not_graspable_reason;
  j["ambiguous"] = inst.ambiguous;
  if (inst.ambiguous) j["ambiguity_reason"] = inst.ambiguity_reason;
  j["support"] = inst.candidate.verification.support;
  j["coarse_support"] = inst.candidate.coarse_verification.support;
  j["icp_rmse_mm"] =
      inst.candidate.icp_run ? nlohmann::json(inst.candidate.icp.rmse_mm) : nlohmann::json();
  j["candidate"] = registration::LocalizationCandidateJson(inst.candidate);
  j["search_ms"] = inst.search_ms;
  return j;
}

nlohmann::json ModelJson(const PartModel& m) {
  return {{"part", m.part.name},
          {"part_file", m.part.file},
          {"model", m.part.model_path},
          {"format", m.source_format},
          {"unit", m.source_unit},
          {"digest", m.digest},
          {"cache_file", m.cache_file},
          {"from_cache", m.from_cache},
          {"cache_note", m.cache_note},
          {"load_ms", m.load_ms},
          {"model_points", m.ppf.points().size()},
          {"diameter_mm", m.ppf.diameter_mm()},
          {"sampling_step_mm", m.ppf.sampling_step_mm()}};
}

}  // namespace

std::string JobResult::Summary() const {
  int requested = 0, found = 0, graspable = 0;
  for (const PartSearch& s : parts.searches) {
    requested += s.requested;
    found += s.found;
  }
  for (const PartInstance& i : parts.instances) graspable += i.graspable ? 1 : 0;
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "%d of %d instances found, %d graspable; %zu sweep points; %.1f ms", found,
                requested, graspable, parts.sweep_points, timings.total_ms);
  return buf;
}

JobRunner::JobRunner(const Job& job, const JobRunOptions& options) : job_(job), options_(options) {
  job_.Check();
  const auto start = Clock::now();
  threads_ = options.threads >= 0 ? options.threads : job.threads;
  cell_ = LoadFrameGraph(job.cell);
  triangulation::LaserPlaneSource plane_source;
  plane_source.laser = job.laser;
  setup_ = triangulation::ScanSetupFromCell(&cell_, job.cell, plane_source,
                                            SweepOptionsOf(job, threads_));
  triangulator_ = std::make_unique<triangulation::Triangulator>(calib::LoadCameraModel(job.camera),
                                                                setup_.laser_plane);
  setup_ms_ = MsSince(start);

  const auto models_start = Clock::now();
  PartModelOptions model_options;
  model_options.cache_dir = job.model_cache;
  model_options.load_mesh = options.load_meshes;
  model_options.threads = threads_;
  auto models = std::make_shared<std::vector<PartModel>>();
  for (const JobPart& p : job.parts) models->push_back(LoadPartModel(p.part, model_options));
  models_ = std::move(models);
  models_ms_ = MsSince(models_start);
  if (options.progress) options.progress("models", 1.0);
}

JobRunner::~JobRunner() = default;

std::optional<JobResult> JobRunner::RunNext(triangulation::ProfileSource& source) {
  const auto start = Clock::now();
  std::optional<triangulation::ProfileSet> profiles = source.NextSweep();
  if (!profiles) return std::nullopt;
  const double profiles_ms = MsSince(start);
  if (options_.progress) options_.progress("profiles", 1.0);
  JobResult result = Run(*profiles, source.Describe());
  if (const std::string loss = source.LastSweepLoss(); !loss.empty()) {
    result.notes.push_back("the sweep is incomplete: " + loss);
  }
  result.timings.profiles_ms = profiles_ms;
  result.timings.total_ms += profiles_ms;
  return result;
}

JobResult JobRunner::Run(const triangulation::ProfileSet& profiles,
                         const std::string& source_name) {
  const auto start = Clock::now();
  JobResult result;
  result.job = job_;
  result.source = source_name;
  result.laser_plane_source = setup_.laser_plane_source;
  result.models = models_;
  result.timings.setup_ms = setup_ms_;
  result.timings.models_ms = models_ms_;

  const auto tri_start = Clock::now();
  result.sweep = triangulation::AssembleSweep(profiles, *triangulator_, setup_.options, &cell_);
  result.timings.triangulation_ms = MsSince(tri_start);
  if (options_.progress) options_.progress("triangulation", 1.0);
  if (result.sweep.cloud.empty()) {
    throw InputError(result.source + ": the sweep has no valid laser points (" +
                     result.sweep.Summary() + ")");
  }

  const auto loc_start = Clock::now();
  LocalizePartsOptions parts_options = PartsOptionsOf(job_, threads_);
  const TransformWithCovarianceResult placement =
      PlacementCovariance(cell_, job_, profiles, setup_.options, &result.notes);
  parts_options.placement_covariance = placement.covariance;
  parts_options.laser_plane = PlaneUncertainty(cell_, job_, setup_, result.sweep, placement,
                                               triangulator_->camera(), &result.notes);
  if (!parts_options.laser_plane || !parts_options.laser_plane->mode_displacements) {
    result.notes.push_back("camera intrinsics uncertainty is not in the pose covariances");
  }
  parts_options.progress = options_.progress;
  std::vector<PartRequest> requests;
  for (std::size_t i = 0; i < job_.parts.size(); ++i) {
    requests.push_back({&(*models_)[i], job_.parts[i].instances});
    const FormDeviation& form = job_.parts[i].part.form_deviation;
    if (form.rms_mm > 0.0) {
      result.notes.push_back(
          "part '" + job_.parts[i].part.name + "': its form deviation from the model (" +
          FormatFixed(form.rms_mm, 2) + " mm RMS over " + FormatFixed(form.correlation_mm, 0) +
          " mm) is in the pose covariances");
    }
  }
  result.parts =
      LocalizeParts(result.sweep.cloud, LinesOfSight(result.sweep), requests, parts_options);
  result.timings.localization_ms = MsSince(loc_start);
  result.timings.run_ms = MsSince(start);
  result.timings.total_ms = setup_ms_ + models_ms_ + result.timings.run_ms;
  return result;
}

JobResult RunJob(const Job& job, const JobRunOptions& options) {
  JobRunner runner(job, options);
  std::shared_ptr<triangulation::ProfileSource> source = options.source;
  if (!source) source = std::make_shared<triangulation::FileProfileSource>(job.profiles);
  std::optional<JobResult> result = runner.RunNext(*source);
  if (!result) throw InputError(source->Describe() + ": the source delivered no sweep");
  return std::move(*result);
}

nlohmann::json PartSearchJson(const PartSearch& s) {
  nlohmann::json rejected = nlohmann::json::array();
  for (const auto& c : s.rejected) rejected.push_back(registration::LocalizationCandidateJson(c));
  return {{"part", s.part},
          {"requested", s.requested},
          {"found", s.found},
          {"message", s.message},
          {"rejected_in_last_search", rejected},
          {"counts",
           {{"sampled_points", s.sampled_points},
            {"reference_points", s.reference_points},
            {"scene_pairs", s.scene_pairs},
            {"votes_cast", s.votes_cast}}},
          {"timings_ms",
           {{"preprocess", s.timings.preprocess_ms},
            {"normals", s.timings.normals_ms},
            {"subsample", s.timings.subsample_ms},
            {"kdtree", s.timings.kdtree_ms},
            {"matching", s.timings.matching_ms},
            {"clustering", s.timings.clustering_ms},
            {"verification", s.timings.verification_ms},
            {"icp", s.timings.icp_ms},
            {"judgement", s.judgement_ms},
            {"total", s.timings.total_ms}}}};
}

nlohmann::json JobResultJson(const JobResult& r) {
  const std::string& target = r.job.target_frame;
  nlohmann::json j;
  j["format"] = kJobResultFormat;
  j["version"] = kJobResultFormatVersion;
  j["job"] = r.job.file;
  j["date"] = UtcTimestampIso();
  j["lasercell_version"] = LASERCELL_VERSION;
  j["target_frame"] = target;
  j["inputs"] = {{"cell", r.job.cell},
                 {"camera", r.job.camera},
                 {"laser_plane", r.laser_plane_source},
                 {"source", r.source},
                 {"trajectory", r.job.linear_record.empty() ? "robot " + r.job.robot
                                                            : "linear " + r.job.linear_record}};
  j["sweep"] = {
      {"profiles", r.sweep.profiles},           {"points", r.parts.sweep_points},
      {"roi_points", r.parts.roi_points},       {"points_with_normals", r.parts.normal_points},
      {"sequence_gaps", r.sweep.sequence_gaps}, {"summary", r.sweep.Summary()}};
  j["all_found"] = r.parts.AllFound();
  j["instances"] = nlohmann::json::array();
  for (const PartInstance& i : r.parts.instances) j["instances"].push_back(InstanceJson(i, target));
  j["searches"] = nlohmann::json::array();
  for (const PartSearch& s : r.parts.searches) j["searches"].push_back(PartSearchJson(s));
  j["models"] = nlohmann::json::array();
  if (r.models) {
    for (const PartModel& m : *r.models) j["models"].push_back(ModelJson(m));
  }
  j["notes"] = r.notes;
  const JobTimings& t = r.timings;
  j["timings_ms"] = {{"setup", t.setup_ms},
                     {"models", t.models_ms},
                     {"profiles", t.profiles_ms},
                     {"triangulation", t.triangulation_ms},
                     {"roi", r.parts.timings.roi_ms},
                     {"normals", r.parts.timings.normals_ms},
                     {"searches", r.parts.timings.searches_ms},
                     {"localization", t.localization_ms},
                     {"run", t.run_ms},
                     {"total", t.total_ms}};
  return j;
}

FrameGraph CellWithInstances(const FrameGraph& cell, const JobResult& result) {
  FrameGraph out = cell;
  InputDigest digest;
  digest.AddFile(result.job.profiles);
  const std::string input_digest = digest.Text();
  for (const PartInstance& inst : result.parts.instances) {
    StaticEdge edge;
    edge.parent = result.job.target_frame;
    edge.child = inst.frame;
    edge.SetParentFromChild(inst.target_from_part);
    if (inst.covariance_valid) edge.covariance = inst.covariance;
    edge.provenance.tool = std::string("lasercell job run ") + LASERCELL_VERSION;
    edge.provenance.date = UtcTimestampIso();
    edge.provenance.input_digest = input_digest;
    char buf[160];
    std::snprintf(buf, sizeof buf, "support %.3f, ICP rmse %.3f mm",
                  inst.candidate.verification.support,
                  inst.candidate.icp_run ? inst.candidate.icp.rmse_mm : -1.0);
    edge.provenance.residual_summary = buf;
    out.SetStaticEdge(edge);
  }
  return out;
}

}  // namespace lasercell::localize
