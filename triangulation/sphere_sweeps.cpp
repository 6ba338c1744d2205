#include "triangulation/sphere_sweeps.hpp"

#include <cmath>
#include <filesystem>
#include <utility>

#include "calib/half_sphere_calibration.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {

namespace {

constexpr const char* kFormat = "lasercell.sphere_sweeps";
constexpr int kVersion = 1;

// The sensor-frame points of one profile by the exact path (the rejected peaks dropped).
std::vector<Eigen::Vector3d> ProfilePoints(const Triangulator& triangulator,
                                           std::uint32_t first_column, const Profile& profile) {
  std::vector<Eigen::Vector3d> all(profile.row_px.size());
  triangulator.Triangulate(profile.row_px, first_column, all, TriangulationPath::kExact);
  std::vector<Eigen::Vector3d> points;
  points.reserve(all.size());
  for (const Eigen::Vector3d& p : all) {
    if (p.allFinite()) points.push_back(p);
  }
  return points;
}

}  // namespace

const SphereSweepSet* SphereSweepList::Find(const std::string& name) const {
  for (const SphereSweepSet& s : sets) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

std::string SphereSweepListYaml(const SphereSweepList& list) {
  std::string text = std::string("format: ") + kFormat + "\nversion: " + std::to_string(kVersion) +
                     "\n# Pose-sweep sets of the vision robot (joints in each profile).\n";
  for (const SphereSweepSet& set : list.sets) {
    text += set.name + ":\n";
    for (const SphereSweepEntry& e : set.sweeps) {
      text += "  - {profiles_file: " + e.profiles_file +
              ", aimed_at_sphere: " + std::to_string(e.aimed_at_sphere) + "}\n";
    }
  }
  return text;
}

SphereSweepList ParseSphereSweepList(const std::string& text, const std::string& name) {
  yaml::Fields root = yaml::Fields::Parse(text, name);
  root.RequireFormat(kFormat, kVersion);
  SphereSweepList list;
  for (const auto& item : root.node()) {
    const std::string key = item.first.as<std::string>();
    if (key == "format" || key == "version") continue;
    root.Known(key.c_str());
    const YAML::Node& seq = item.second;
    if (!seq.IsSequence() || seq.size() == 0) {
      root.Fail(key, "must be a non-empty list of {profiles_file, aimed_at_sphere}");
    }
    SphereSweepSet set;
    set.name = key;
    for (std::size_t i = 0; i < seq.size(); ++i) {
      yaml::Fields entry(seq[i], root.Path(key) + "[" + std::to_string(i) + "]", name);
      SphereSweepEntry e;
      entry.ReadRequired("profiles_file", &e.profiles_file);
      entry.ReadRequired("aimed_at_sphere", &e.aimed_at_sphere);
      if (e.aimed_at_sphere < 0) entry.Fail("aimed_at_sphere", "must be >= 0");
      if (e.profiles_file.empty()) entry.Fail("profiles_file", "must name a profile file");
      entry.Done();
      set.sweeps.push_back(std::move(e));
    }
    list.sets.push_back(std::move(set));
  }
  root.Done();
  return list;
}

std::vector<calib::SphereSweep> LoadSphereSweeps(const std::string& path, const std::string& set,
                                                 const calib::CameraModel& camera,
                                                 const Eigen::Vector4d& plane_in_sensor,
                                                 const TriangulatorOptions& options) {
  const SphereSweepList list = ParseSphereSweepList(io::ReadFileBytes(path), path);
  const SphereSweepSet* chosen = list.Find(set);
  if (chosen == nullptr) {
    std::string names;
    for (const SphereSweepSet& s : list.sets) names += (names.empty() ? "" : " or ") + s.name;
    throw FileError(path, "has no sweep set '" + set + "' (try --set " +
                              (names.empty() ? std::string("eye_in_hand or joint_poses") : names) +
                              ")");
  }
  const Triangulator triangulator(camera, plane_in_sensor, options);
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::vector<calib::SphereSweep> sweeps;
  for (const SphereSweepEntry& e : chosen->sweeps) {
    std::filesystem::path full = dir / e.profiles_file;
    if (!std::filesystem::exists(full)) full = dir.parent_path() / e.profiles_file;
    const ProfileSet profiles = ReadProfiles(full.string());
    if (profiles.header.joint_count == 0) {
      throw FileError(full.string(),
                      "the profiles carry no joint values; joint identification "
                      "and hand-eye need the robot joints of every profile");
    }
    if (static_cast<int>(profiles.header.image_width) != camera.width_px() ||
        static_cast<int>(profiles.header.image_height) != camera.height_px()) {
      throw FileError(full.string(), "image size " + std::to_string(profiles.header.image_width) +
                                         "x" + std::to_string(profiles.header.image_height) +
                                         " differs from the camera model's");
    }
    calib::SphereSweep sweep;
    sweep.name = e.profiles_file;
    sweep.sphere = e.aimed_at_sphere;
    for (const Profile& p : profiles.profiles) {
      sweep.profiles.push_back(
          {p.joints_rad, ProfilePoints(triangulator, profiles.header.first_column, p)});
    }
    sweeps.push_back(std::move(sweep));
  }
  return sweeps;
}

SphereSweepProblem LoadSphereSweepProblem(const SphereSweepProblemSpec& spec) {
  SphereSweepProblem p;
  p.graph = LoadFrameGraph(spec.cell);
  p.robot = calib::FindRobot(p.graph, spec.robot, spec.cell);
  p.flange_from_sensor =
      calib::FlangeFromSensor(p.graph, p.robot.flange, spec.sensor_frame, spec.cell);
  const calib::CameraModel camera = calib::LoadCameraModel(spec.camera);
  Eigen::Vector4d plane;
  if (spec.laser_plane) {
    plane = *spec.laser_plane;
    const double n = plane.head<3>().norm();
    if (!(n > 0) || !plane.allFinite()) {
      throw OptionError("laser_plane: the normal must be finite and non-zero");
    }
    plane /= n;
  } else {
    plane = calib::CellLaserPlane(p.graph, spec.cell, spec.sensor_frame);
  }
  p.sweeps = LoadSphereSweeps(spec.sweeps, spec.set, camera, plane);
  p.solver.point_sigma_mm = spec.point_sigma_mm;
  p.solver.radius_mm = spec.radius_mm;
  p.solver.max_points_per_sweep = spec.max_points_per_sweep;
  if (!spec.touches.empty()) {
    const calib::KnownSphereCentres k = calib::CentresFromTouches(
        calib::ParseTouchesYaml(io::ReadFileBytes(spec.touches), spec.touches), spec.touches,
        p.graph, p.robot.base, spec.radius_mm, spec.up);
    p.solver.known_centres_in_base = k.centres_in_base;
    p.solver.known_centre_sigma_mm = k.sigma_mm;
    if (p.solver.radius_mm <= 0) p.solver.radius_mm = k.radius_mm;
  }
  return p;
}

namespace {

calib::SphereSweepRun RunOf(const SphereSweepProblemSpec& spec, std::size_t sweeps,
                            bool with_hand_eye, bool dh_deltas) {
  return {spec.robot, spec.sweeps, spec.set, sweeps, spec.touches, with_hand_eye, dh_deltas};
}

}  // namespace

JointCalibration CalibrateJointsFromSweeps(const SphereSweepProblemSpec& spec, bool with_hand_eye,
                                           bool dh_deltas) {
  SphereSweepProblem in = LoadSphereSweepProblem(spec);
  in.solver.estimate_hand_eye = with_hand_eye;
  in.solver.estimate_dh_deltas = dh_deltas;
  JointCalibration out;
  out.result = calib::IdentifyRobot(in.robot.chain, in.flange_from_sensor, in.sweeps, in.solver);
  out.run = RunOf(spec, in.sweeps.size(), with_hand_eye, dh_deltas);
  out.cell = std::move(in.graph);
  out.cell.SetRobot(spec.robot, out.result.robot);
  if (with_hand_eye) {
    out.cell.SetStaticEdge(calib::FlangeSensorEdge(
        in.robot.flange, spec.sensor_frame, out.result.flange_from_sensor,
        out.result.flange_from_sensor_covariance, "lasercell calibrate joints --with-handeye",
        out.result.rms_mm, out.result.points_used, in.sweeps.size()));
  }
  return out;
}

LaserHandEyeCalibration CalibrateLaserHandEyeFromSweeps(const SphereSweepProblemSpec& spec) {
  SphereSweepProblem in = LoadSphereSweepProblem(spec);
  calib::LaserHandEyeOptions options;
  options.solver = in.solver;
  LaserHandEyeCalibration out;
  out.result =
      calib::CalibrateLaserHandEye(in.robot.chain, in.flange_from_sensor, in.sweeps, options);
  out.run = RunOf(spec, in.sweeps.size(), false, false);
  out.cell = std::move(in.graph);
  out.cell.SetStaticEdge(
      calib::FlangeSensorEdge(in.robot.flange, spec.sensor_frame, out.result.flange_from_sensor,
                              out.result.covariance, "lasercell calibrate handeye-laser",
                              out.result.rms_mm, out.result.points_used, in.sweeps.size()));
  return out;
}

SphereSweepProblemSpec LaserHandEyeSpecDefaults() {
  SphereSweepProblemSpec spec;
  spec.set = "eye_in_hand";
  spec.max_points_per_sweep = 5000;
  return spec;
}

}  // namespace lasercell::triangulation
