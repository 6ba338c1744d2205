// `lasercell calibrate joints` (joint-offset identification of the vision robot from sphere
// sweeps, calib/joint_identification.hpp) and `lasercell calibrate handeye-laser` (eye-in-hand
// laser variant, calib/laser_hand_eye.hpp). Both read the sweep list (records/sphere_sweeps.yaml:
// sets of {profiles_file, aimed_at_sphere}), the profiles (.lcp with joints), the camera model
// and the laser plane, triangulate each peak by an exact ray/plane step, solve, and update only
// their own parts of CELL.yaml: the robot's DH table (joints) or the vision_flange <-> sensor
// edge (handeye-laser, or joints --with-handeye).
//
// The laser plane comes from --laser-plane nx,ny,nz,d (sensor frame, n . p + d = 0, mm) until
// cell.yaml carries it.
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/internal/kinematic_profile_points.hpp"
#include "calib/joint_identification.hpp"
#include "calib/laser_hand_eye.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"
#include "tools/commands.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::tools {
namespace {

using report::HtmlReport;
using report::WriteHtmlReport;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr const char* kToolName = "lasercell calibrate joints";

struct JointsArgs {
  std::string cell, camera, sweeps, set, report, json, robot = "vision_robot", output;
  std::string laser_plane, touches;
  std::string sensor_frame = "sensor";
  bool with_handeye = false, dh_deltas = false;
  double point_sigma_mm = 0.1, radius_mm = 0;
  int max_points = 300;
};

Eigen::Vector4d ParsePlane(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw OptionError("--laser-plane: '" + item + "' is not a number; give nx,ny,nz,d");
    }
  }
  if (v.size() != 4) {
    throw OptionError("--laser-plane: expected 4 numbers nx,ny,nz,d (sensor frame, mm), got " +
                      std::to_string(v.size()));
  }
  Eigen::Vector4d p(v[0], v[1], v[2], v[3]);
  const double n = p.head<3>().norm();
  if (!(n > 0) || !p.allFinite()) throw OptionError("--laser-plane: the normal must be non-zero");
  return p / n;
}

/// The sweeps of one set of records/sphere_sweeps.yaml, triangulated.
std::vector<calib::SphereSweep> LoadSweeps(const std::string& path, const std::string& set,
                                           const calib::CameraModel& camera,
                                           const Eigen::Vector4d& plane) {
  const std::string text = io::ReadFileBytes(path);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FileError(path, std::string("not YAML: ") + e.what());
  }
  try {
    if (!root.IsMap() || !root["format"] ||
        root["format"].as<std::string>() != "lasercell.sphere_sweeps") {
      throw FileError(path, "not a sphere-sweep list (format: lasercell.sphere_sweeps expected)");
    }
    if (!root["version"] || root["version"].as<int>() != 1) {
      throw FileError(path, "unsupported version (this lasercell reads version 1)");
    }
  } catch (const YAML::Exception&) {
    throw FileError(path, "malformed format/version fields");
  }
  const YAML::Node list = root[set];
  if (!list || !list.IsSequence() || list.size() == 0) {
    throw FileError(path, "has no sweep set '" + set + "' (try --set eye_in_hand or joint_poses)");
  }
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::vector<calib::SphereSweep> sweeps;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node e = list[i];
    if (!e["profiles_file"] || !e["aimed_at_sphere"]) {
      throw FileError(path, set + " entry " + std::to_string(i + 1) +
                                " needs profiles_file and aimed_at_sphere");
    }
    std::string file;
    int sphere = 0;
    try {
      file = e["profiles_file"].as<std::string>();
      sphere = e["aimed_at_sphere"].as<int>();
    } catch (const YAML::Exception&) {
      throw FileError(path, set + " entry " + std::to_string(i + 1) +
                                ": profiles_file must be a path and aimed_at_sphere an integer");
    }
    std::filesystem::path full = dir / file;
    if (!std::filesystem::exists(full)) full = dir.parent_path() / file;  // relative to the set
    const triangulation::ProfileSet profiles = triangulation::ReadProfiles(full.string());
    if (profiles.header.joint_count == 0) {
      throw FileError(full.string(), "the profiles carry no joint values; joint identification "
                                     "and hand-eye need the robot joints of every profile");
    }
    if (static_cast<int>(profiles.header.image_width) != camera.width_px() ||
        static_cast<int>(profiles.header.image_height) != camera.height_px()) {
      throw FileError(full.string(), "image size " + std::to_string(profiles.header.image_width) +
                                         "x" + std::to_string(profiles.header.image_height) +
                                         " differs from the camera model's");
    }
    calib::SphereSweep sweep;
    sweep.name = file;
    sweep.sphere = sphere;
    for (const triangulation::Profile& p : profiles.profiles) {
      sweep.profiles.push_back({p.joints_rad, calib::internal::ProfilePointsOnPlane(
                                                  camera, plane, profiles.header.first_column,
                                                  p.row_px)});
    }
    sweeps.push_back(std::move(sweep));
  }
  return sweeps;
}

/// Sphere centres in the robot base from the handling robot's touches of the sphere tops
/// (records/touches.yaml: tops in handling_base, the sphere radius, the touch sigma): centre =
/// top - radius * up (cell +z), mapped into `base` through the cell's frame graph.
struct KnownCentres {
  std::vector<Eigen::Vector3d> centres_in_base;
  double sigma_mm = 0;
  double radius_mm = 0;
};

KnownCentres CentresFromTouches(const std::string& path, const FrameGraph& graph,
                                const std::string& base) {
  YAML::Node root;
  try {
    root = YAML::Load(io::ReadFileBytes(path));
  } catch (const YAML::Exception& e) {
    throw FileError(path, std::string("not YAML: ") + e.what());
  }
  KnownCentres k;
  std::string frame;
  std::vector<std::pair<int, Eigen::Vector3d>> tops;
  try {
    if (!root.IsMap() || !root["format"] || root["format"].as<std::string>() != "lasercell.touches" ||
        !root["version"] || root["version"].as<int>() != 1) {
      throw FileError(path, "not a touch list (format: lasercell.touches, version: 1 expected)");
    }
    frame = root["frame"].as<std::string>();
    k.radius_mm = root["sphere_radius_mm"].as<double>();
    k.sigma_mm = root["stated_sigma_mm"].as<double>();
    for (const YAML::Node& t : root["touches"]) {
      const std::vector<double> p = t["point_in_handling_base"].as<std::vector<double>>();
      if (p.size() != 3) throw FileError(path, "a touch point needs 3 coordinates (mm)");
      tops.emplace_back(t["sphere"].as<int>(), Eigen::Vector3d(p[0], p[1], p[2]));
    }
  } catch (const YAML::Exception& e) {
    throw FileError(path, std::string("malformed touch list: ") + e.what());
  }
  if (!(k.radius_mm > 0) || !(k.sigma_mm > 0)) {
    throw FileError(path, "sphere_radius_mm and stated_sigma_mm must be positive");
  }
  if (!graph.HasFrame(frame) || !graph.Connected(base, frame)) {
    throw FileError(path, "its frame '" + frame + "' is not connected to '" + base +
                              "' in the cell; the cell must hold both robots' bases");
  }
  const Eigen::Isometry3d base_from_frame = graph.Transform(base, frame);
  // "Up" is the cell's +z when the cell frame exists, else the touch frame's own z.
  const Eigen::Vector3d up_in_frame =
      graph.HasFrame("cell") && graph.Connected("cell", frame)
          ? Eigen::Vector3d(graph.Transform(frame, "cell").linear().col(2))
          : Eigen::Vector3d::UnitZ();
  k.centres_in_base.assign(tops.size(), Eigen::Vector3d::Constant(NAN));
  for (const auto& [sphere, top] : tops) {
    if (sphere < 0 || sphere >= static_cast<int>(tops.size())) {
      throw FileError(path, "sphere index " + std::to_string(sphere) + " out of range");
    }
    k.centres_in_base[static_cast<std::size_t>(sphere)] =
        base_from_frame * (top - k.radius_mm * up_in_frame);
  }
  for (const Eigen::Vector3d& c : k.centres_in_base) {
    if (!c.allFinite()) throw FileError(path, "every sphere needs exactly one touch");
  }
  return k;
}

std::string NowIso() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

/// The static edge joining the flange and the sensor, and flange_from_sensor.
Eigen::Isometry3d FlangeFromSensor(const FrameGraph& graph, const std::string& flange,
                                   const std::string& sensor, const std::string& cell) {
  for (const StaticEdge& e : graph.static_edges()) {
    if (e.parent == flange && e.child == sensor) return e.ParentFromChild();
    if (e.parent == sensor && e.child == flange) return e.ParentFromChild().inverse();
  }
  throw FileError(cell, "has no static edge between '" + flange + "' and '" + sensor +
                            "' (the hand-eye transform); add an initial guess");
}

struct RobotInCell {
  DhChain chain;
  std::string base, flange;
};

RobotInCell FindRobot(const FrameGraph& graph, const std::string& robot, const std::string& cell) {
  const auto* chain = dynamic_cast<const DhChain*>(&graph.Robot(robot));
  if (!chain) throw FileError(cell, "robot '" + robot + "' is not a DH chain");
  for (const DynamicEdge& e : graph.dynamic_edges()) {
    if (e.robot == robot) return {*chain, e.parent, e.child};
  }
  throw FileError(cell, "robot '" + robot + "' has no dynamic edge (base -> flange)");
}

nlohmann::json PoseJson(const Eigen::Isometry3d& pose) {
  const QuaternionPose q = QuaternionPose::FromIsometry(pose);
  return {{"translation_mm", {q.translation_mm.x(), q.translation_mm.y(), q.translation_mm.z()}},
          {"rotation_wxyz", {q.rotation.w(), q.rotation.x(), q.rotation.y(), q.rotation.z()}}};
}

nlohmann::json ObservabilityJson(const calib::ObservabilityReport& o) {
  nlohmann::json dirs = nlohmann::json::array();
  for (const calib::UnidentifiableDirection& d : o.directions) {
    dirs.push_back({{"parameters", d.parameters},
                    {"null_vector_components", d.components},
                    {"relative_singular_value", d.relative_singular_value},
                    {"action", d.fixed_parameter.empty()
                                   ? "none (degenerate)"
                                   : "fixed " + d.fixed_parameter + " at its input value"}});
  }
  std::vector<double> sv(o.singular_values.data(),
                         o.singular_values.data() + o.singular_values.size());
  return {{"column_scaled", true},
          {"singular_values", sv},
          {"condition_number", o.condition_number},
          {"unidentifiable", dirs}};
}

nlohmann::json SweepsJson(const std::vector<calib::SweepResidual>& sweeps) {
  nlohmann::json out = nlohmann::json::array();
  for (const calib::SweepResidual& s : sweeps) {
    out.push_back({{"name", s.name}, {"sphere", s.sphere}, {"points", s.points},
                   {"rms_mm", s.rms_mm}, {"mean_mm", s.mean_mm}, {"max_abs_mm", s.max_abs_mm}});
  }
  return out;
}

nlohmann::json SpheresJson(const std::vector<Eigen::Vector3d>& c,
                           const std::vector<Eigen::Vector3d>& s) {
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t i = 0; i < c.size(); ++i) {
    out.push_back({{"sphere", i},
                   {"centre_in_base_mm", {c[i].x(), c[i].y(), c[i].z()}},
                   {"sigma_mm", {s[i].x(), s[i].y(), s[i].z()}}});
  }
  return out;
}

nlohmann::json CovarianceJson(const Matrix6d& c) {
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 6; ++i) {
    rows.push_back(std::vector<double>{c(i, 0), c(i, 1), c(i, 2), c(i, 3), c(i, 4), c(i, 5)});
  }
  return {{"order", "rotation vector rad (3), translation mm (3); left perturbation"},
          {"matrix", rows},
          {"sigma_rotation_deg",
           {std::sqrt(c(0, 0)) * kRadToDeg, std::sqrt(c(1, 1)) * kRadToDeg,
            std::sqrt(c(2, 2)) * kRadToDeg}},
          {"sigma_translation_mm", {std::sqrt(c(3, 3)), std::sqrt(c(4, 4)), std::sqrt(c(5, 5))}}};
}

void WriteJson(const std::string& path, const nlohmann::json& j) {
  if (!path.empty()) io::WriteFileAtomically(path, j.dump(2) + "\n");
}

/// Report plots shared by both commands: per-sweep errors, residual histogram, singular values.
void AddCommonReport(HtmlReport& report, const std::vector<calib::SweepResidual>& sweeps,
                     const std::vector<double>& residuals, const calib::ObservabilityReport& obs) {
  report.AddHeading("Per-pose errors");
  std::vector<std::string> labels;
  std::vector<double> rms, mean;
  std::vector<std::vector<std::string>> rows;
  for (const calib::SweepResidual& s : sweeps) {
    labels.push_back(std::filesystem::path(s.name).stem().string());
    rms.push_back(s.rms_mm);
    mean.push_back(s.mean_mm);
    char buf[3][32];
    std::snprintf(buf[0], 32, "%.4f", s.rms_mm);
    std::snprintf(buf[1], 32, "%.4f", s.mean_mm);
    std::snprintf(buf[2], 32, "%.4f", s.max_abs_mm);
    rows.push_back({s.name, std::to_string(s.sphere), std::to_string(s.points), buf[0], buf[1],
                    buf[2]});
  }
  report.AddBars("RMS point-to-sphere distance per pose", labels, rms, "rms (mm)");
  report.AddBars("Mean signed distance per pose: a pose error shows as a bias", labels, mean,
                 "mean (mm)");
  report.AddTable({"sweep", "sphere", "points", "rms (mm)", "mean (mm)", "max |r| (mm)"}, rows);
  report.AddHeading("Residuals");
  report.AddHistogram("Point-to-sphere distances", residuals, "signed distance (mm)", 40);
  report.AddHeading("Observability");
  report.AddParagraph(obs.Summary());
  std::vector<std::string> idx;
  std::vector<double> logsv;
  for (Eigen::Index i = 0; i < obs.singular_values.size(); ++i) {
    idx.push_back(std::to_string(i + 1));
    logsv.push_back(std::log10(std::max(1e-300, obs.singular_values[i])));
  }
  report.AddBars("Singular values of the column-scaled identification Jacobian", idx, logsv,
                 "log10 singular value");
  for (const calib::UnidentifiableDirection& d : obs.directions) {
    std::string names;
    for (const std::string& n : d.parameters) names += (names.empty() ? "" : ", ") + n;
    report.AddWarning("not identifiable from these poses: " + names +
                      (d.fixed_parameter.empty() ? "" : " -> fixed " + d.fixed_parameter +
                                                            " at its input value"));
  }
}

/// Correlation table of a covariance.
void AddCorrelation(HtmlReport& report, const Eigen::MatrixXd& cov,
                    const std::vector<std::string>& names, const std::string& title) {
  report.AddHeading(title);
  std::vector<std::string> header = {""};
  for (const std::string& n : names) header.push_back(n);
  std::vector<std::vector<std::string>> rows;
  for (Eigen::Index i = 0; i < cov.rows(); ++i) {
    std::vector<std::string> row = {names[static_cast<std::size_t>(i)]};
    for (Eigen::Index j = 0; j < cov.cols(); ++j) {
      char buf[32];
      if (i == j) {
        std::snprintf(buf, sizeof buf, "σ %.3g", std::sqrt(cov(i, i)));
      } else {
        std::snprintf(buf, sizeof buf, "%.2f", cov(i, j) / std::sqrt(cov(i, i) * cov(j, j)));
      }
      row.push_back(buf);
    }
    rows.push_back(std::move(row));
  }
  report.AddTable(header, rows);
}

// The laser plane: --laser-plane when given, else the cell's calibrated `laser` plane.
Eigen::Vector4d LaserPlane(const JointsArgs& a, const FrameGraph& graph) {
  if (!a.laser_plane.empty()) return ParsePlane(a.laser_plane);
  const auto it = graph.laser_planes().find("laser");
  if (it == graph.laser_planes().end()) {
    throw OptionError(a.cell + " has no laser plane 'laser': run `lasercell calibrate laser` "
                      "first or give --laser-plane nx,ny,nz,d");
  }
  if (it->second.frame != a.sensor_frame) {
    throw OptionError(a.cell + ": laser plane 'laser' is given in frame '" + it->second.frame +
                      "', expected '" + a.sensor_frame + "'");
  }
  const Eigen::Vector3d& n = it->second.normal;
  return {n.x(), n.y(), n.z(), it->second.OffsetMm()};
}

void RunJoints(const JointsArgs& a) {
  const FrameGraph graph = LoadFrameGraph(a.cell);
  const RobotInCell robot = FindRobot(graph, a.robot, a.cell);
  const Eigen::Isometry3d x0 = FlangeFromSensor(graph, robot.flange, a.sensor_frame, a.cell);
  const calib::CameraModel camera = calib::LoadCameraModel(a.camera);
  const std::vector<calib::SphereSweep> sweeps =
      LoadSweeps(a.sweeps, a.set, camera, LaserPlane(a, graph));
  calib::JointIdentificationOptions o;
  o.estimate_hand_eye = a.with_handeye;
  o.estimate_dh_deltas = a.dh_deltas;
  o.point_sigma_mm = a.point_sigma_mm;
  o.radius_mm = a.radius_mm;
  o.max_points_per_sweep = a.max_points;
  if (!a.touches.empty()) {
    const KnownCentres k = CentresFromTouches(a.touches, graph, robot.base);
    o.known_centres_in_base = k.centres_in_base;
    o.known_centre_sigma_mm = k.sigma_mm;
    if (o.radius_mm <= 0) o.radius_mm = k.radius_mm;
  }
  const calib::JointIdentificationResult r = calib::IdentifyRobot(robot.chain, x0, sweeps, o);

  FrameGraph updated = graph;
  updated.SetRobot(a.robot, r.robot);
  if (a.with_handeye) {
    StaticEdge edge;
    edge.parent = robot.flange;
    edge.child = a.sensor_frame;
    edge.SetParentFromChild(r.flange_from_sensor);
    edge.covariance = r.flange_from_sensor_covariance;
    edge.provenance = {std::string(kToolName) + " --with-handeye", NowIso(), "",
                       "rms " + std::to_string(r.rms_mm) + " mm over " +
                           std::to_string(r.points_used) + " points, " +
                           std::to_string(sweeps.size()) + " sweeps"};
    updated.SetStaticEdge(edge);
  }
  SaveFrameGraph(a.output.empty() ? a.cell : a.output, updated);

  nlohmann::json offsets = nlohmann::json::array();
  nlohmann::json dh = nlohmann::json::array();
  for (std::size_t k = 0; k < r.parameter_names.size(); ++k) {
    const bool angle = k < 6 || k >= 18;
    const double unit = angle ? kRadToDeg : 1.0;
    const std::vector<double> values = DhParameterVector(r.robot);
    if (k < 6) {
      offsets.push_back({{"joint", k + 1},
                         {"offset_deg", values[k] * unit},
                         {"sigma_deg", r.parameter_sigmas[k] * unit},
                         {"correction_deg", r.parameter_corrections[k] * unit},
                         {"estimated", static_cast<bool>(r.parameter_estimated[k])}});
    } else if (a.dh_deltas) {
      dh.push_back({{"parameter", r.parameter_names[k]},
                    {"unit", angle ? "deg" : "mm"},
                    {"value", values[k] * unit},
                    {"correction", r.parameter_corrections[k] * unit},
                    {"sigma", r.parameter_sigmas[k] * unit},
                    {"estimated", static_cast<bool>(r.parameter_estimated[k])}});
    }
  }
  nlohmann::json cov_rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < r.covariance.rows(); ++i) {
    std::vector<double> row(r.covariance.cols());
    for (Eigen::Index j = 0; j < r.covariance.cols(); ++j) row[j] = r.covariance(i, j);
    cov_rows.push_back(row);
  }
  nlohmann::json j = {
      {"format", "lasercell.joint_calibration"},
      {"version", 1},
      {"robot", a.robot},
      {"sweep_set", a.set},
      {"sphere_centres", a.touches.empty() ? "free" : "from touches " + a.touches},
      {"converged", r.converged},
      {"termination", r.termination},
      {"iterations", r.iterations},
      {"residual_rms_mm", r.rms_mm},
      {"points_used", r.points_used},
      {"points_rejected", r.points_rejected},
      {"variance_factor", r.variance_factor},
      {"joint_offsets", offsets},
      {"radius_mm", r.radius_mm},
      {"radius_sigma_mm", r.radius_sigma_mm},
      {"spheres", SpheresJson(r.sphere_centres_in_base, r.sphere_centre_sigmas)},
      {"sweeps", SweepsJson(r.sweeps)},
      {"observability", ObservabilityJson(r.observability)},
      {"covariance", {{"parameters", r.covariance_names}, {"matrix", cov_rows},
                      {"units", "rad for angles, mm for lengths"}}},
      {"warnings", r.warnings}};
  if (a.dh_deltas) j["dh_parameters"] = dh;
  if (a.with_handeye) {
    j["vision_flange_from_sensor"] = PoseJson(r.flange_from_sensor);
    j["vision_flange_from_sensor_covariance"] = CovarianceJson(*r.flange_from_sensor_covariance);
  }
  WriteJson(a.json, j);

  if (!a.report.empty()) {
    HtmlReport report("lasercell calibrate joints: " + a.robot);
    report.AddKeyValues({{"result", r.Summary()},
                         {"sweeps", a.sweeps + " (" + a.set + ", " +
                                        std::to_string(sweeps.size()) + ")"},
                         {"hand-eye", a.with_handeye ? "estimated" : "held (from the cell)"},
                         {"DH deltas", a.dh_deltas ? "estimated" : "not estimated"}});
    for (const std::string& w : r.warnings) report.AddWarning(w);
    std::vector<std::vector<std::string>> rows;
    for (int k = 0; k < 6; ++k) {
      char v[32], s[32], c[32];
      std::snprintf(v, 32, "%.5f", r.robot.joints()[k].joint_offset_rad * kRadToDeg);
      std::snprintf(s, 32, "%.5f", r.parameter_sigmas[k] * kRadToDeg);
      std::snprintf(c, 32, "%.5f", r.parameter_corrections[k] * kRadToDeg);
      rows.push_back({std::to_string(k + 1), v, s, c,
                      r.parameter_estimated[k] ? "estimated" : "fixed (not identifiable)"});
    }
    report.AddHeading("Joint offsets");
    report.AddTable({"joint", "offset (deg)", "1σ (deg)", "correction (deg)", "status"}, rows);
    AddCommonReport(report, r.sweeps, r.residuals_mm, r.observability);
    AddCorrelation(report, r.covariance, r.covariance_names, "Covariance (σ on the diagonal, "
                                                             "correlations off it)");
    WriteHtmlReport(a.report, report);
  }
  std::printf("%s -> %s\n", r.Summary().c_str(), (a.output.empty() ? a.cell : a.output).c_str());
}

void RunHandEyeLaser(const JointsArgs& a) {
  const FrameGraph graph = LoadFrameGraph(a.cell);
  const RobotInCell robot = FindRobot(graph, a.robot, a.cell);
  const Eigen::Isometry3d x0 = FlangeFromSensor(graph, robot.flange, a.sensor_frame, a.cell);
  const calib::CameraModel camera = calib::LoadCameraModel(a.camera);
  const std::vector<calib::SphereSweep> sweeps =
      LoadSweeps(a.sweeps, a.set, camera, LaserPlane(a, graph));
  calib::LaserHandEyeOptions o;
  o.solver.point_sigma_mm = a.point_sigma_mm;
  o.solver.radius_mm = a.radius_mm;
  o.solver.max_points_per_sweep = a.max_points;
  if (!a.touches.empty()) {
    const KnownCentres k = CentresFromTouches(a.touches, graph, robot.base);
    o.solver.known_centres_in_base = k.centres_in_base;
    o.solver.known_centre_sigma_mm = k.sigma_mm;
    if (o.solver.radius_mm <= 0) o.solver.radius_mm = k.radius_mm;
  }
  const calib::LaserHandEyeResult r = calib::CalibrateLaserHandEye(robot.chain, x0, sweeps, o);
  FrameGraph updated = graph;
  StaticEdge edge;
  edge.parent = robot.flange;
  edge.child = a.sensor_frame;
  edge.SetParentFromChild(r.flange_from_sensor);
  edge.covariance = r.covariance;
  edge.provenance = {"lasercell calibrate handeye-laser", NowIso(), "",
                     "rms " + std::to_string(r.rms_mm) + " mm over " +
                         std::to_string(r.points_used) + " points, " +
                         std::to_string(sweeps.size()) + " sweeps"};
  updated.SetStaticEdge(edge);
  SaveFrameGraph(a.output.empty() ? a.cell : a.output, updated);
  const nlohmann::json j = {
      {"format", "lasercell.laser_hand_eye"},
      {"version", 1},
      {"robot", a.robot},
      {"sweep_set", a.set},
      {"converged", r.converged},
      {"vision_flange_from_sensor", PoseJson(r.flange_from_sensor)},
      {"covariance", CovarianceJson(r.covariance)},
      {"residual_rms_mm", r.rms_mm},
      {"points_used", r.points_used},
      {"radius_mm", r.radius_mm},
      {"radius_sigma_mm", r.radius_sigma_mm},
      {"spheres", SpheresJson(r.sphere_centres_in_base, r.sphere_centre_sigmas)},
      {"sweeps", SweepsJson(r.sweeps)},
      {"observability", ObservabilityJson(r.observability)},
      {"warnings", r.warnings}};
  WriteJson(a.json, j);
  if (!a.report.empty()) {
    HtmlReport report("lasercell calibrate handeye-laser");
    report.AddKeyValues({{"result", r.Summary()},
                         {"vision_flange_from_sensor", PoseToFileNotation(r.flange_from_sensor)},
                         {"sweeps", a.sweeps + " (" + a.set + ", " +
                                        std::to_string(sweeps.size()) + ")"}});
    for (const std::string& w : r.warnings) report.AddWarning(w);
    AddCommonReport(report, r.sweeps, r.residuals_mm, r.observability);
    AddCorrelation(report, r.covariance, {"rx", "ry", "rz", "tx", "ty", "tz"},
                   "Hand-eye covariance (rad, mm; σ on the diagonal, correlations off it)");
    WriteHtmlReport(a.report, report);
  }
  std::printf("%s -> %s\n", r.Summary().c_str(), (a.output.empty() ? a.cell : a.output).c_str());
}

void AddShared(CLI::App* cmd, JointsArgs& a) {
  cmd->add_option("--cell", a.cell, "cell.yaml with the robot and the flange<->sensor edge")
      ->required();
  cmd->add_option("--camera", a.camera, "Sensor camera model (.cameramodel)")->required();
  cmd->add_option("--sweeps", a.sweeps, "Sphere-sweep list (records/sphere_sweeps.yaml)")
      ->required();
  cmd->add_option("--laser-plane", a.laser_plane,
                  "Laser plane nx,ny,nz,d in the sensor frame (n.p + d = 0, mm); default: the "
                  "cell's calibrated 'laser' plane");
  cmd->add_option("--touches", a.touches,
                  "Sphere tops touched by the handling robot (records/touches.yaml): fixes the "
                  "sphere centres (mapped through the cell), making joint 1 identifiable");
  cmd->add_option("--robot", a.robot, "Robot name in the cell (default vision_robot)");
  cmd->add_option("--sensor-frame", a.sensor_frame, "Sensor frame name (default sensor)");
  cmd->add_option("--point-sigma", a.point_sigma_mm, "A-priori point noise, mm (default 0.1)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--sphere-radius", a.radius_mm, "Initial sphere radius, mm (0: from the data)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-points", a.max_points,
                  "Points per sweep used (default " + std::to_string(a.max_points) + ")")
      ->check(CLI::Range(10, 100000));
  cmd->add_option("--output", a.output, "Write the updated cell here (default: --cell in place)");
  cmd->add_option("--report", a.report, "HTML report");
  cmd->add_option("--json", a.json, "JSON result");
}

}  // namespace

void AddCalibrateJointsCommands(CLI::App& calibrate) {
  CLI::App* joints = calibrate.add_subcommand(
      "joints", "Joint offsets (and optionally DH deltas, hand-eye) of the vision robot from "
                "sphere sweeps; updates only the robot model in CELL.yaml");
  auto ja = std::make_shared<JointsArgs>();
  ja->set = "joint_poses";
  AddShared(joints, *ja);
  joints->add_option("--set", ja->set, "Sweep set in the list (default joint_poses)");
  joints->add_flag("--with-handeye", ja->with_handeye,
                   "Also estimate vision_flange_from_sensor (updates that edge too)");
  joints->add_flag("--dh-deltas", ja->dh_deltas, "Also estimate a, d, alpha of every joint");
  joints->callback([ja] { RunJoints(*ja); });

  CLI::App* he = calibrate.add_subcommand(
      "handeye-laser", "Eye-in-hand laser sensor: vision_flange_from_sensor from sphere sweeps "
                       "taken from several robot poses (robot model held)");
  auto ha = std::make_shared<JointsArgs>();
  ha->set = "eye_in_hand";
  // Hand-eye has only 6 unknowns (+ spheres): every point helps, and it stays fast (~1 s).
  ha->max_points = 5000;
  AddShared(he, *ha);
  he->add_option("--set", ha->set, "Sweep set in the list (default eye_in_hand)");
  he->callback([ha] { RunHandEyeLaser(*ha); });
}

}  // namespace lasercell::tools
