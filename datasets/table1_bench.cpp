#include "datasets/table1_bench.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"
#include "core/pose_covariance.hpp"
#include "core/se3.hpp"
#include "core/stats.hpp"
#include "datasets/capture_calibration.hpp"
#include "datasets/sim_config.hpp"
#include "datasets/sim_profile.hpp"
#include "datasets/simulate.hpp"
#include "datasets/simulate_records.hpp"
#include "localize/job_run.hpp"
#include "registration/localize_options_io.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::datasets {
namespace {

// The chi-square quantile with 3 degrees of freedom at P = 0.9973 (the Gaussian's 3 sigma).
constexpr double kChiSquare3Dof3Sigma = 14.156;

// P(|z| <= 3) of a standard normal: the share a correct sigma keeps within 3 sigma.
double Within3Sigma() { return std::erf(3.0 / std::sqrt(2.0)); }

struct Trial {
  int cell = 0;
  std::string seat;
  bool found = false;
  double ppf_error_mm = NAN, icp_error_mm = NAN;
  double ppf_rotation_error_deg = NAN;  // coarse pose's rotation from the truth
  Eigen::Vector3d ppf_error_in_part = Eigen::Vector3d::Zero();  // coarse hole error, part frame
  bool graspable = false;
  std::string reason;
  Eigen::Vector3d error = Eigen::Vector3d::Zero();  // found - true hole centre, handling_base
  // The hole centre's reported covariance (mm^2, handling_base; zero when the pose has none)
  // and its terms; the squared Mahalanobis distance of the error under it (chi-square with 3
  // dof if the covariance is right).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d icp_term = Eigen::Matrix3d::Zero(), placement_term = Eigen::Matrix3d::Zero(),
                  laser_plane_term = Eigen::Matrix3d::Zero();
  double mahalanobis_sq = NAN;
  bool refined_locally = false;  // the hole grasp's own fit decided its pose
  double local_shift_mm = 0;     // and moved the hole by this much from the part's pose
  double localization_ms = 0, triangulation_ms = 0, run_ms = 0;
  // The reported 1-sigma of the hole centre per axis.
  Eigen::Vector3d Sigma() const { return covariance.diagonal().cwiseMax(0.0).cwiseSqrt(); }
};

// A cell's calibration against the simulator's truth (the benchmark reads truth/; the job never
// does): the laser plane's normal (deg) and offset d of n . p + d = 0 (mm), handling_base <-
// sensor's rotation (deg) and translation (mm) at the sensor origin, and how far it moves the
// pallet deck's centre, where the seats lie (mm).
struct CalibrationErrors {
  double plane_normal_deg = NAN, plane_offset_mm = NAN;
  double sensor_rotation_deg = NAN, sensor_origin_mm = NAN, sensor_at_deck_mm = NAN;
};

CalibrationErrors AgainstTruth(const SimConfig& config, const std::string& sim,
                               const std::string& cell_file) {
  CalibrationErrors e;
  const FrameGraph cell = LoadFrameGraph(cell_file);
  const LaserPlaneEntry& plane = cell.laser_planes().at("laser");
  const SimSensorTruth sensor = ReadSensorTruth(sim + "/truth/sensor.yaml");
  Eigen::Vector3d n = plane.normal.normalized();
  double d = plane.OffsetMm();
  if (n.dot(sensor.laser_normal_in_sensor) < 0) {
    n = -n;
    d = -d;
  }
  e.plane_normal_deg = std::acos(std::clamp(n.dot(sensor.laser_normal_in_sensor), -1.0, 1.0)) *
                       180.0 / std::numbers::pi;
  e.plane_offset_mm = d - sensor.laser_d_mm;
  const CellTruth truth = MakeCellTruth(config);
  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  const Eigen::Isometry3d true_hb_from_sensor =
      hb_from_cell * MakeLinearSweep(config, truth.sensor).At(0.0);
  const Eigen::Isometry3d hb_from_sensor = cell.Transform("handling_base", "sensor");
  e.sensor_rotation_deg =
      RotationDistance(hb_from_sensor, true_hb_from_sensor) * 180.0 / std::numbers::pi;
  e.sensor_origin_mm = (hb_from_sensor.translation() - true_hb_from_sensor.translation()).norm();
  const Eigen::Vector3d deck_in_sensor =
      true_hb_from_sensor.inverse() * (hb_from_cell * Eigen::Vector3d(0, 0, kPalletHeightMm));
  e.sensor_at_deck_mm =
      (hb_from_sensor * deck_in_sensor - true_hb_from_sensor * deck_in_sensor).norm();
  return e;
}

// What one cell's calibration gave: the calibration, or why it was refused.
struct CellCalibration {
  int cell = 0;
  std::uint64_t seed = 0;
  bool accepted = false;
  CaptureCalibration calibration;
  CalibrationErrors errors;
  std::string refusal;
};

struct Stats {
  double mean = NAN, sd = NAN, p99 = NAN, max = NAN;
};

Stats Summarize(std::vector<double> v) {
  Stats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  double sum = 0, sq = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  for (double x : v) sq += (x - s.mean) * (x - s.mean);
  s.sd = v.size() > 1 ? std::sqrt(sq / static_cast<double>(v.size() - 1)) : 0.0;
  s.p99 = v[static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(v.size()))) - 1];
  s.max = v.back();
  return s;
}

SimConfig ConfigOf(const Table1Options& options, int cell, int seats) {
  SimConfig config = options.sim_config.empty() ? SimConfigForProfile(options.profile)
                                                : LoadSimConfig(options.sim_config);
  config.seed = options.seed + static_cast<std::uint64_t>(cell);
  config.seat_count = seats;
  config.capture_seats = config.capture_planes = config.capture_spheres = true;
  config.capture_chessboard_images = config.capture_touches = true;
  config.capture_trajectory = config.capture_laser_line_images = false;
  config.capture_eye_in_hand = config.capture_joint_poses = config.capture_hand_eye_images = false;
  return config;
}

localize::Job JobOf(const std::string& sim, const CaptureCalibration& cal,
                    const Table1Options& options) {
  localize::Job job;
  if (!options.options_file.empty())
    job.settings = registration::ReadLocalizeOptions(options.options_file);
  job.cell = cal.cell_file;
  job.camera = cal.camera_file;
  job.profiles = sim + "/profiles/seat_000.lcp";
  job.linear_record = sim + "/records/linear_sweep.yaml";
  job.threads = options.threads;
  job.model_cache = options.work_dir + "/model_cache";
  localize::JobPart part;
  part.file = sim + "/models/seat.part.yaml";
  part.part = localize::ReadPartFile(part.file);
  if (!options.options_file.empty()) part.part.model_options = job.settings.model;
  job.parts.push_back(part);
  return job;
}

Trial RunTrial(localize::JobRunner& runner, const std::string& sim, const std::string& seat,
               const Eigen::Isometry3d& truth, const Eigen::Vector3d& hole_in_part) {
  Trial t;
  t.seat = seat;
  const localize::JobResult r =
      runner.Run(triangulation::ReadProfiles(sim + "/profiles/" + seat + ".lcp"), seat);
  t.localization_ms = r.timings.localization_ms;
  t.triangulation_ms = r.timings.triangulation_ms;
  t.run_ms = r.timings.run_ms;
  if (r.parts.instances.empty()) {
    t.reason = r.parts.searches.front().message;
    return t;
  }
  const localize::PartInstance& inst = r.parts.instances.front();
  const Eigen::Vector3d hole_true = truth * hole_in_part;
  t.found = true;
  t.ppf_error_mm = (inst.candidate.coarse_scene_from_model * hole_in_part - hole_true).norm();
  t.ppf_error_in_part = truth.linear().transpose() *
                        (inst.candidate.coarse_scene_from_model * hole_in_part - hole_true);
  t.ppf_rotation_error_deg =
      RotationDistance(inst.candidate.coarse_scene_from_model, truth) * 180.0 / std::numbers::pi;
  // What the handling robot is sent: the hole grasp's pose (its own fit when the part file
  // asks for one), its origin the hole centre.
  const auto grasp = std::find_if(inst.grasps.begin(), inst.grasps.end(),
                                  [](const localize::GraspPose& g) { return g.name == "hole"; });
  if (grasp == inst.grasps.end()) throw InternalError("Table I: the seat has no 'hole' grasp");
  t.error = grasp->target_from_grasp.translation() - hole_true;
  t.icp_error_mm = t.error.norm();
  t.refined_locally = grasp->refined_locally;
  t.local_shift_mm = grasp->local_shift_mm;
  t.graspable = inst.graspable;
  t.reason = inst.not_graspable_reason;
  if (inst.covariance_valid) {
    const auto term = [&](const Matrix6d& c) {
      return PointCovariance(grasp->target_from_grasp, c, Eigen::Vector3d::Zero());
    };
    const Eigen::Matrix3d cov = term(grasp->covariance);
    t.covariance = cov;
    t.icp_term = term(grasp->covariance - inst.covariance_terms.placement -
                      inst.covariance_terms.laser_plane);
    t.placement_term = term(inst.covariance_terms.placement);
    t.laser_plane_term = term(inst.covariance_terms.laser_plane);
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(cov);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
      t.mahalanobis_sq = t.error.dot(ldlt.solve(t.error));
    }
  }
  return t;
}

std::string Row(const char* name, const Stats& s) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "| %s | %.3f | %.3f | %.3f | %.3f |", name, s.mean, s.sd, s.p99,
                s.max);
  return buf;
}

nlohmann::json StatsJson(const Stats& s) {
  return {{"mean", s.mean}, {"sd", s.sd}, {"p99", s.p99}, {"max", s.max}};
}

nlohmann::json Summary(const Table1Options& options, const std::vector<Trial>& trials,
                       const std::vector<CellCalibration>& cals) {
  std::vector<double> ppf, ppf_rotation, icp, loc, tri, run, overhead;
  int within = 0, graspable = 0, beyond = 0, covered = 0, axes = 0;
  nlohmann::json rows = nlohmann::json::array();
  for (const Trial& t : trials) {
    loc.push_back(t.localization_ms);
    tri.push_back(t.triangulation_ms);
    run.push_back(t.run_ms);
    overhead.push_back(t.run_ms - t.localization_ms - t.triangulation_ms);
    rows.push_back({{"cell", t.cell},
                    {"seat", t.seat},
                    {"found", t.found},
                    {"ppf_error_mm", json::FiniteOrNull(t.ppf_error_mm)},
                    {"icp_error_mm", json::FiniteOrNull(t.icp_error_mm)},
                    {"ppf_rotation_error_deg", json::FiniteOrNull(t.ppf_rotation_error_deg)},
                    {"ppf_error_in_part_mm", json::Vector(t.ppf_error_in_part)},
                    {"graspable", t.graspable},
                    {"reason", t.reason},
                    {"error_mm", json::Vector(t.error)},
                    {"sigma_mm", json::Vector(t.Sigma())},
                    {"covariance_mm2",
                     {{"total", json::Rows(t.covariance)},
                      {"icp", json::Rows(t.icp_term)},
                      {"placement", json::Rows(t.placement_term)},
                      {"laser_plane", json::Rows(t.laser_plane_term)}}},
                    {"mahalanobis_sq", json::FiniteOrNull(t.mahalanobis_sq)},
                    {"grasp_refined_locally", t.refined_locally},
                    {"local_shift_mm", t.local_shift_mm},
                    {"localization_ms", t.localization_ms}});
    if (!t.found) continue;
    ppf.push_back(t.ppf_error_mm);
    ppf_rotation.push_back(t.ppf_rotation_error_deg);
    icp.push_back(t.icp_error_mm);
    within += t.icp_error_mm <= 10.0 ? 1 : 0;
    graspable += t.graspable ? 1 : 0;
    bool out3 = false;
    const Eigen::Vector3d sigma = t.Sigma();
    for (int k = 0; k < 3; ++k) {
      if (!(sigma[k] > 0)) continue;
      ++axes;
      covered += std::abs(t.error[k]) <= sigma[k] ? 1 : 0;
      out3 |= std::abs(t.error[k]) > 3.0 * sigma[k];
    }
    beyond += out3 ? 1 : 0;
  }
  const double median_tri = Median(tri), median_loc = Median(loc);
  nlohmann::json calibrations = nlohmann::json::array(), refused = nlohmann::json::array();
  int placements_localized = 0;
  for (const CellCalibration& c : cals) {
    if (!c.accepted) {
      refused.push_back({{"cell", c.cell}, {"seed", c.seed}, {"reason", c.refusal}});
      continue;
    }
    placements_localized += options.placements / options.cells;
    calibrations.push_back(
        {{"cell", c.cell},
         {"seed", c.seed},
         {"camera", c.calibration.camera_summary},
         {"laser", c.calibration.laser_summary},
         {"spheres", c.calibration.spheres_summary},
         {"errors_against_truth",
          {{"laser_plane_normal_deg", json::FiniteOrNull(c.errors.plane_normal_deg)},
           {"laser_plane_offset_mm", json::FiniteOrNull(c.errors.plane_offset_mm)},
           {"sensor_rotation_deg", json::FiniteOrNull(c.errors.sensor_rotation_deg)},
           {"sensor_origin_mm", json::FiniteOrNull(c.errors.sensor_origin_mm)},
           {"sensor_at_deck_mm", json::FiniteOrNull(c.errors.sensor_at_deck_mm)}}}});
  }
  return {{"format", "lasercell.bench_table1"},
          {"version", 2},
          {"placements", options.placements},
          {"cells", options.cells},
          {"seed", options.seed},
          {"threads", options.threads},
          {"options_file", options.options_file},
          {"profile", options.sim_config.empty() ? options.profile : std::string()},
          {"sim_config", options.sim_config},
          {"calibrations", calibrations},
          {"refused_calibrations", refused},
          {"placements_localized", placements_localized},
          {"found", static_cast<int>(icp.size())},
          {"within_10mm", within},
          {"graspable", graspable},
          {"ppf_error_mm", StatsJson(Summarize(ppf))},
          {"ppf_rotation_error_deg", StatsJson(Summarize(ppf_rotation))},
          {"icp_error_mm", StatsJson(Summarize(icp))},
          {"sigma_coverage", axes > 0 ? static_cast<double>(covered) / axes : 0.0},
          {"beyond_3_sigma", beyond},
          // P(some |z_k| > 3 of three independent standard normals) x found.
          {"beyond_3_sigma_expected",
           (1.0 - std::pow(Within3Sigma(), 3)) * static_cast<double>(icp.size())},
          {"median_localization_ms", median_loc},
          {"median_triangulation_ms", median_tri},
          {"median_run_ms", Median(run)},
          {"job_overhead_fraction", Median(overhead) / (median_tri + median_loc)},
          {"trials", rows}};
}

// The reported covariance against the error over the found trials, added to `summary`:
// beyond_3_sigma_ellipsoid (squared Mahalanobis distance above the chi-square quantile at
// 99.73 %, 3 dof) and the count a correct Gaussian covariance would give, mahalanobis_sq_mean
// (3 for a correct covariance) and median_sigma_mm (the median reported 1-sigma of the hole
// centre per axis of handling_base, mm: in all and per term).
void AddUncertaintySummary(const std::vector<Trial>& trials, nlohmann::json* summary) {
  int tested = 0, beyond = 0;
  double sum = 0.0;
  const char* names[4] = {"total", "icp", "placement", "laser_plane"};
  std::vector<double> sigma[4][3];
  for (const Trial& t : trials) {
    if (!t.found || !std::isfinite(t.mahalanobis_sq)) continue;
    ++tested;
    beyond += t.mahalanobis_sq > kChiSquare3Dof3Sigma ? 1 : 0;
    sum += t.mahalanobis_sq;
    const Eigen::Matrix3d* terms[4] = {&t.covariance, &t.icp_term, &t.placement_term,
                                       &t.laser_plane_term};
    for (int term = 0; term < 4; ++term) {
      for (int k = 0; k < 3; ++k) {
        sigma[term][k].push_back(std::sqrt(std::max(0.0, (*terms[term])(k, k))));
      }
    }
  }
  nlohmann::json medians = nlohmann::json::object();
  for (int term = 0; term < 4; ++term) {
    nlohmann::json axes = nlohmann::json::array();
    for (int k = 0; k < 3; ++k) {
      axes.push_back(json::FiniteOrNull(sigma[term][k].empty() ? NAN : Median(sigma[term][k])));
    }
    medians[names[term]] = axes;
  }
  (*summary)["beyond_3_sigma_ellipsoid"] = beyond;
  (*summary)["beyond_3_sigma_ellipsoid_expected"] =
      (1.0 - Within3Sigma()) * static_cast<double>(tested);
  (*summary)["mahalanobis_sq_mean"] = json::FiniteOrNull(tested > 0 ? sum / tested : NAN);
  (*summary)["median_sigma_mm"] = medians;
}

// One simulated cell: its captures and `seats` placements, calibrated from the captures alone,
// every seat localized through one JobRunner. A refused calibration localizes nothing.
std::vector<Trial> RunCell(const Table1Options& options, int cell, int seats,
                           const ProgressCallback& progress, std::vector<CellCalibration>* cals) {
  const std::string dir =
      options.cells == 1 ? options.work_dir : options.work_dir + "/cell_" + std::to_string(cell);
  const std::string sim = dir + "/sim";
  const SimConfig config = ConfigOf(options, cell, seats);
  const std::string name = "cell " + std::to_string(cell + 1) + " of " +
                           std::to_string(options.cells) + " (seed " + std::to_string(config.seed) +
                           ")";
  // The captures are a pure function of the simulator settings: reuse them when asked and the
  // settings they were made with are these.
  const std::string stamp = sim + "/table1_sim_config.yaml";
  const std::string config_yaml = SimConfigToYaml(config);
  if (!(options.reuse_captures && std::filesystem::exists(stamp) &&
        io::ReadFileBytes(stamp) == config_yaml)) {
    SimulateCell(config, sim, progress, 0);
    io::WriteFileAtomically(stamp, config_yaml);
  } else {
    ReportProgress(progress, name + ": reusing the captures in " + sim, 1.0);
  }
  CellCalibration cc;
  cc.cell = cell;
  cc.seed = config.seed;
  try {
    cc.calibration =
        CalibrateCaptureFolder(sim, dir + "/cal", config.chessboard.board, progress, 0);
    cc.accepted = true;
    cc.errors = AgainstTruth(config, sim, cc.calibration.cell_file);
  } catch (const InputError& e) {  // FileError is an InputError: a refusal, not a crash
    cc.refusal = e.what();
  }
  cals->push_back(cc);
  ReportProgress(progress, name + (cc.accepted ? ": calibrated" : ": calibration REFUSED"), 1.0);
  if (!cc.accepted) return {};

  // The model cache is shared: every cell's seat is the same part.
  localize::JobRunner runner(JobOf(sim, cc.calibration, options));
  const FrameGraph truth = LoadFrameGraph(sim + "/truth/cell.yaml");
  const Eigen::Vector3d hole =
      runner.job().parts.front().part.Grasp("hole").part_from_grasp.translation_mm;
  std::vector<Trial> trials;
  for (int i = 0; i < seats; ++i) {
    char seat[32];
    std::snprintf(seat, sizeof seat, "seat_%03d", i);
    trials.push_back(RunTrial(runner, sim, seat, truth.Transform("handling_base", seat), hole));
    trials.back().cell = cell;
    ReportProgress(progress, name + ": localizing", static_cast<double>(i + 1) / seats);
  }
  return trials;
}

}  // namespace

void Table1Options::Check() const {
  if (placements < 1) throw OptionError("placements " + std::to_string(placements) + " < 1");
  if (cells < 1) throw OptionError("cells " + std::to_string(cells) + " < 1");
  if (placements % cells != 0) {
    throw OptionError("placements " + std::to_string(placements) + " is not a multiple of cells " +
                      std::to_string(cells) + ": every cell localizes the same number of seats");
  }
  if (threads < 0) throw OptionError("threads " + std::to_string(threads) + " < 0");
  if (work_dir.empty()) throw OptionError("work_dir is empty: name a folder for the captures");
  if (sim_config.empty()) ParseSimProfile(profile);
}

nlohmann::json RunTable1Bench(const Table1Options& options, const ProgressCallback& progress) {
  options.Check();
  std::vector<CellCalibration> cals;
  std::vector<Trial> trials;
  for (int cell = 0; cell < options.cells; ++cell) {
    const std::vector<Trial> t =
        RunCell(options, cell, options.placements / options.cells, progress, &cals);
    trials.insert(trials.end(), t.begin(), t.end());
  }
  nlohmann::json summary = Summary(options, trials, cals);
  AddUncertaintySummary(trials, &summary);
  return summary;
}

// The accepted cells' calibrations against the truth: median and max of each error, beside the
// targets of the calibration issues ("" when the result predates the errors).
std::string CalibrationErrorsMarkdown(const nlohmann::json& cals) {
  const struct {
    const char* key;
    const char* name;
    const char* target;
  } rows[] = {
      {"laser_plane_normal_deg", "laser plane normal (deg)", "0.01"},
      {"laser_plane_offset_mm", "laser plane offset d, absolute (mm)", "0.02"},
      {"sensor_rotation_deg", "handling_base <- sensor rotation (deg)", "0.01"},
      {"sensor_origin_mm", "handling_base <- sensor translation at the sensor origin (mm)",
       "(0.05 at the spheres; ~0.7 m of lever arm here)"},
      {"sensor_at_deck_mm", "handling_base <- sensor at the pallet deck's centre (mm)", "0.05"},
  };
  std::string md;
  for (const auto& row : rows) {
    std::vector<double> v;
    for (const nlohmann::json& c : cals) {
      if (!c.contains("errors_against_truth")) continue;
      const nlohmann::json& x = c.at("errors_against_truth").at(row.key);
      if (x.is_number()) v.push_back(std::abs(x.get<double>()));
    }
    if (v.empty()) return "";
    std::sort(v.begin(), v.end());
    char buf[300];
    std::snprintf(buf, sizeof buf, "| %s | %.4f | %.4f | %s |\n", row.name, Median(v), v.back(),
                  row.target);
    md += buf;
  }
  return "| calibration against the truth, " + std::to_string(cals.size()) +
         " accepted cell(s) | median | max | target |\n|---|---|---|---|\n" + md + "\n";
}

std::string Table1Markdown(const nlohmann::json& j) {
  char buf[1200];
  std::string md =
      "### Table I through the calibrated chain (`lasercell bench table1 --placements " +
      std::to_string(j.at("placements").get<int>()) + " --cells " +
      std::to_string(j.at("cells").get<int>()) + " --seed " +
      std::to_string(j.at("seed").get<std::uint64_t>()) +
      (j.value("profile", std::string()).empty()
           ? std::string()
           : " --profile " + j.at("profile").get<std::string>()) +
      (j.value("sim_config", std::string()).empty()
           ? std::string()
           : " --config " + j.at("sim_config").get<std::string>()) +
      (j.value("options_file", std::string()).empty()
           ? std::string()
           : " --options " + j.at("options_file").get<std::string>()) +
      "`)\n\n";
  const nlohmann::json& cals = j.at("calibrations");
  const nlohmann::json& refused = j.at("refused_calibrations");
  md += "Calibrated from the simulated captures (never the truth), " +
        std::to_string(j.at("cells").get<int>()) + " cell(s), each from its own captures";
  if (!cals.empty()) {
    md += "; the first accepted: " + cals[0].at("camera").get<std::string>() + "; " +
          cals[0].at("laser").get<std::string>() + "; " + cals[0].at("spheres").get<std::string>();
  }
  md += ".\n\n" + CalibrationErrorsMarkdown(cals);
  if (!refused.empty()) {
    md += std::to_string(refused.size()) +
          " cell(s) refused their calibration and localized nothing (their placements are not "
          "counted below):\n\n";
    for (const nlohmann::json& r : refused) {
      md += "- cell " + std::to_string(r.at("cell").get<int>()) + " (seed " +
            std::to_string(r.at("seed").get<std::uint64_t>()) +
            "): " + r.at("reason").get<std::string>() + "\n";
    }
    md += "\n";
  }
  md +=
      "| hole-centre error in handling_base (mm) | mean | sigma | p99 | max "
      "|\n|---|---|---|---|---|\n";
  const auto stats = [&](const char* key) {
    const nlohmann::json& s = j.at(key);
    const auto value = [&](const char* k) {
      return s.at(k).is_number() ? s.at(k).get<double>() : NAN;
    };
    return Stats{value("mean"), value("sd"), value("p99"), value("max")};
  };
  md += Row("after PPF (coarse pose)", stats("ppf_error_mm")) + "\n";
  md += Row("after ICP", stats("icp_error_mm")) + "\n";
  md += "| Skotheim et al. 2012, 10 placements: after PPF / after ICP | 10.69 / 1.81 | | | |\n\n";
  if (j.contains("ppf_rotation_error_deg")) {
    const Stats r = stats("ppf_rotation_error_deg");
    std::snprintf(
        buf, sizeof buf,
        "The coarse pose's rotation error: mean %.2f deg, p99 %.2f deg, max %.2f deg.\n\n", r.mean,
        r.p99, r.max);
    md += buf;
  }
  const int localized = j.at("placements_localized").get<int>();
  const int thread_count = j.value("threads", 1);
  const std::string threads = thread_count == 1   ? std::string("one thread")
                              : thread_count == 0 ? std::string("all cores")
                                                  : std::to_string(thread_count) + " threads";
  const auto num = [&](const char* key) {
    return j.at(key).is_number() ? j.at(key).get<double>() : NAN;  // null: nothing measured
  };
  std::snprintf(
      buf, sizeof buf,
      "Found %d of %d placements localized; within the gripper's +-10 mm: %d (%.1f %%; the "
      "paper: 10 of 10); reported graspable: %d. Reported 1-sigma of the hole centre covers the "
      "error %.1f %% of the time per axis (a Gaussian: 68.3 %%), %d of %d found "
      "placements exceed 3 sigma on some axis (three independent Gaussian axes: %.1f). "
      "Time per part, %s: localization "
      "median %.1f ms, triangulation median %.1f ms, job run median %.1f ms (the job's "
      "own work: %.1f %% of triangulation + localization); the paper: ~1.7 s.\n",
      j.at("found").get<int>(), localized, j.at("within_10mm").get<int>(),
      localized > 0 ? 100.0 * j.at("within_10mm").get<int>() / localized : 0.0,
      j.at("graspable").get<int>(), 100.0 * num("sigma_coverage"),
      j.at("beyond_3_sigma").get<int>(), j.at("found").get<int>(), num("beyond_3_sigma_expected"),
      threads.c_str(), num("median_localization_ms"), num("median_triangulation_ms"),
      num("median_run_ms"), 100.0 * num("job_overhead_fraction"));
  md += buf;
  if (j.contains("beyond_3_sigma_ellipsoid")) {
    std::snprintf(buf, sizeof buf,
                  "\nOutside the reported covariance's 3-sigma ellipsoid (squared Mahalanobis "
                  "distance > %.3f, chi-square with 3 dof): %d placements (a correct "
                  "Gaussian covariance: %.1f).\n",
                  kChiSquare3Dof3Sigma, j.at("beyond_3_sigma_ellipsoid").get<int>(),
                  num("beyond_3_sigma_ellipsoid_expected"));
    md += buf;
  }
  if (j.contains("median_sigma_mm") && j.contains("mahalanobis_sq_mean")) {
    const nlohmann::json& m = j.at("median_sigma_mm");
    const auto axes = [&](const char* term) {
      std::string out;
      for (int k = 0; k < 3; ++k) {
        const nlohmann::json& v = m.at(term).at(k);
        out += (k ? " / " : "") + (v.is_number() ? FormatFixed(v.get<double>(), 4) : "-");
      }
      return out;
    };
    md += "\nMedian reported 1-sigma of the hole centre along handling_base x / y / z (mm): " +
          axes("total") + " in all; ICP " + axes("icp") + ", calibrated placement " +
          axes("placement") + ", laser plane " + axes("laser_plane") +
          ". Mean squared Mahalanobis distance of the error: " +
          (j.at("mahalanobis_sq_mean").is_number()
               ? FormatFixed(j.at("mahalanobis_sq_mean").get<double>(), 2)
               : std::string("-")) +
          " (3 for a correct covariance).\n";
  }
  return md;
}

}  // namespace lasercell::datasets
