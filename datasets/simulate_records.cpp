#include "datasets/simulate_records.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell::datasets {

namespace sim_text {

std::string Num(double v) {
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  return FormatDouble(v);
}

std::string Vec(const Eigen::Vector3d& v) {
  // Appends (not "[" + std::string): GCC 12 -O2 reports a false -Wrestrict on the latter.
  std::string s = "[";
  s += Num(v.x());
  s += ", ";
  s += Num(v.y());
  s += ", ";
  s += Num(v.z());
  s += "]";
  return s;
}

std::string Pose(const Eigen::Isometry3d& p) { return PoseToFileNotation(p); }

}  // namespace sim_text

namespace {
using sim_text::Num;
using sim_text::Pose;
using sim_text::Vec;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
}  // namespace

std::string LinearSweepTruthYaml(const LinearSweep& sweep, const Eigen::Isometry3d& hb_from_cell,
                                 const SimConfig& config) {
  std::ostringstream o;
  o << "    sweep:\n      type: linear\n"
    << "      t0_ns: " << config.timing.start_ns << "\n"
    << "      cell_from_sensor_at_t0: " << Pose(sweep.cell_from_sensor_start) << "\n"
    << "      velocity_mm_s_in_cell: " << Vec(sweep.velocity_mm_s) << "\n"
    << "      handling_base_from_sensor_at_t0: "
    << Pose(hb_from_cell * sweep.cell_from_sensor_start)
    << "\n      velocity_mm_s_in_handling_base: "
    << Vec(hb_from_cell.linear() * sweep.velocity_mm_s) << "\n";
  return o.str();
}

triangulation::LinearSweepRecord LinearSweepRecordOf(const LinearSweep& sweep,
                                                     const SimConfig& config) {
  triangulation::LinearSweepRecord r;
  r.t0_ns = config.timing.start_ns;
  r.velocity_mm_s_in_sensor =
      sweep.cell_from_sensor_start.linear().transpose() * sweep.velocity_mm_s;
  r.speed_mm_s = sweep.velocity_mm_s.norm();
  return r;
}

std::string ExposureTimesTruthYaml(const SweepResult& result, const SimConfig& config) {
  if (config.timing.timestamp_noise_s <= 0) return "";  // timestamps are the true times
  std::ostringstream o;
  o << "      true_exposure_ns: [";
  for (std::size_t i = 0; i < result.exposure_time_s.size(); ++i) {
    o << (i ? ", " : "")
      << config.timing.start_ns +
             static_cast<std::int64_t>(std::llround(result.exposure_time_s[i] * 1e9));
  }
  o << "]\n";
  return o.str();
}

std::string CaptureHeaderYaml(const CaptureReport& r) {
  return "  - name: " + r.name + "\n    kind: " + r.kind +
         "\n    profiles_file: " + r.profiles_file +
         "\n    profiles: " + std::to_string(r.profiles) +
         "\n    valid_peaks: " + std::to_string(r.valid_peaks) + "\n";
}

std::string SeatTruthYaml(const SeatCapture& s, const CellTruth& truth,
                          const Eigen::Isometry3d& hb_from_cell) {
  const Eigen::Isometry3d hb_from_part = hb_from_cell * s.placement.cell_from_part;
  std::ostringstream o;
  o << "    part: seat\n    part_frame: " << s.name << "\n"
    << "    placement: {shift_x_mm: " << Num(s.placement.shift_x_mm)
    << ", shift_y_mm: " << Num(s.placement.shift_y_mm)
    << ", tilt_x_deg: " << Num(s.placement.tilt_x_rad * kRadToDeg)
    << ", tilt_y_deg: " << Num(s.placement.tilt_y_rad * kRadToDeg)
    << ", yaw_deg: " << Num(s.placement.yaw_rad * kRadToDeg) << "}\n"
    << "    cell_from_part: " << Pose(s.placement.cell_from_part) << "\n"
    << "    handling_base_from_part: " << Pose(hb_from_part) << "\n"
    << "    hole_center_in_handling_base: " << Vec(hb_from_part * truth.seat.hole_center_in_part)
    << "\n    hole_axis_in_handling_base: "
    << Vec(hb_from_part.linear() * truth.seat.hole_axis_in_part) << "\n"
    << "    hole_center_in_cell: "
    << Vec(s.placement.cell_from_part * truth.seat.hole_center_in_part) << "\n";
  return o.str();
}

std::string SensorTruthYaml(const CellTruth& t, const SimConfig& c) {
  const LaserPlane& l = t.sensor.laser;
  const Eigen::Vector4d coeff = l.Coefficients();
  const auto& cam = c.sensor.camera;
  std::ostringstream o;
  o << "format: lasercell.sim_sensor\nversion: 1\n"
    << "# The sensor frame is the camera frame (mrcal convention: x columns, y rows, z optical\n"
    << "# axis); the laser plane is n . p + d = 0 in it, mm.\n"
    << "sensor_from_camera: " << Pose(Eigen::Isometry3d::Identity()) << "\n"
    << "vision_flange_from_sensor: " << Pose(t.vision_flange_from_sensor) << "\n"
    << "laser_plane_in_sensor:\n"
    << "  normal: " << Vec(l.normal_in_sensor) << "\n"
    << "  d_mm: " << Num(coeff[3]) << "\n"
    << "  point_mm: " << Vec(l.origin_in_sensor) << "\n"
    << "laser:\n  emitter_in_sensor_mm: " << Vec(l.origin_in_sensor) << "\n"
    << "  central_ray_in_sensor: " << Vec(l.center_in_sensor) << "\n"
    << "  fan_angle_rad: " << Num(l.fan_angle_rad) << "\n"
    << "  wavelength_nm: 660\n"
    << "measuring_range_along_laser_mm: [" << Num(t.sensor.central_range_mm[0]) << ", "
    << Num(t.sensor.central_range_mm[1]) << "]\n"
    << "camera:\n  model_file: camera.cameramodel\n  lensmodel: LENSMODEL_OPENCV8\n"
    << "  imagersize: [" << cam.width_px << ", " << cam.height_px << "]\n"
    << "  intrinsics: [";
  const auto v = cam.MrcalVector();
  for (std::size_t i = 0; i < v.size(); ++i) o << (i ? ", " : "") << Num(v[i]);
  o << "]\n  pixel_pitch_um: 10.6\n  focal_length_mm: " << Num(cam.fx_px * 10.6e-3) << "\n";
  o << "noise:\n  row_sigma_px: " << Num(c.render.row_sigma_px)
    << "\n  intensity_sigma: " << Num(c.render.intensity_sigma)
    << "\n  dropout_probability: " << Num(c.render.dropout_probability)
    << "\n  speckle_sigma_px: " << Num(c.render.speckle_sigma_px)
    << "\n  speckle_correlation_px: " << Num(c.render.speckle_correlation_px)
    << "\n  speckle_intensity_sigma: " << Num(c.render.speckle_intensity_sigma)
    << "\n  min_intensity: " << Num(c.render.min_intensity)
    << "\n  timing_jitter_s: " << Num(c.timing.jitter_s)
    << "\n  timestamp_noise_s: " << Num(c.timing.timestamp_noise_s) << "\n";
  return o.str();
}

std::string RobotsTruthYaml(const CellTruth& t) {
  std::ostringstream o;
  o << "format: lasercell.sim_robots\nversion: 1\n"
    << "vision_robot:\n  model: UR5 (core NominalUr5, standard DH)\n"
    << "  # The true robot = nominal DH table + these offsets added to every joint angle.\n"
    << "  joint_offsets_rad: [";
  for (std::size_t i = 0; i < t.joint_offsets_rad.size(); ++i) {
    o << (i ? ", " : "") << Num(t.joint_offsets_rad[i]);
  }
  o << "]\n  joint_offsets_deg: [";
  for (std::size_t i = 0; i < t.joint_offsets_rad.size(); ++i) {
    o << (i ? ", " : "") << Num(t.joint_offsets_rad[i] * kRadToDeg);
  }
  o << "]\n  # ... and these errors added to the nominal a_i and d_i (mm).\n  dh_a_errors_mm: [";
  for (std::size_t i = 0; i < t.dh_a_errors_mm.size(); ++i) {
    o << (i ? ", " : "") << Num(t.dh_a_errors_mm[i]);
  }
  o << "]\n  dh_d_errors_mm: [";
  for (std::size_t i = 0; i < t.dh_d_errors_mm.size(); ++i) {
    o << (i ? ", " : "") << Num(t.dh_d_errors_mm[i]);
  }
  o << "]\nhandling_robot:\n  model: Nachi SC15F stand-in (datasets ApproximateNachiSc15f)\n";
  return o.str();
}

std::string CapturesPreambleYaml(const SimConfig& config, const CellTruth& truth) {
  std::ostringstream o;
  o << "format: lasercell.sim_truth\nversion: 1\nseed: " << config.seed << "\n"
    << "# Poses: parent_from_child as {translation_mm, rotation_wxyz}; frames as in cell.yaml.\n"
    << "cell_from_handling_base: " << Pose(truth.layout.cell_from_handling_base) << "\n"
    << "cell_from_vision_base: " << Pose(truth.layout.cell_from_vision_base) << "\n"
    << "hole_center_in_part: " << Vec(truth.seat.hole_center_in_part) << "\n"
    << "captures:\n";
  return o.str();
}

Eigen::Vector4d SimSensorTruth::LaserPlane() const {
  return {laser_normal_in_sensor.x(), laser_normal_in_sensor.y(), laser_normal_in_sensor.z(),
          laser_d_mm};
}

SimSensorTruth ParseSensorTruth(const std::string& text, const std::string& name) {
  yaml::Fields f = yaml::Fields::Parse(text, name);
  f.RequireFormat("lasercell.sim_sensor", 1);
  SimSensorTruth t;
  if (!f.Has("laser_plane_in_sensor")) {
    throw FileError(name, "has no laser_plane_in_sensor {normal, d_mm}");
  }
  yaml::Fields plane = f.Sub("laser_plane_in_sensor");
  plane.ReadRequired("normal", &t.laser_normal_in_sensor);
  plane.ReadRequired("d_mm", &t.laser_d_mm);
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  if (plane.Read("point_mm", &point)) t.laser_point_in_sensor_mm = point;
  plane.Done();
  // Informative here (poses, lens, noise; the range may be .inf, which yaml::Fields refuses).
  for (const char* key : {"sensor_from_camera", "vision_flange_from_sensor", "laser",
                          "measuring_range_along_laser_mm", "camera", "noise"}) {
    f.Known(key);
  }
  f.Done();
  if (!t.laser_normal_in_sensor.allFinite() || !std::isfinite(t.laser_d_mm) ||
      std::abs(t.laser_normal_in_sensor.norm() - 1.0) > 1e-6) {
    plane.Fail("normal", "must be a finite unit vector with a finite d_mm");
  }
  return t;
}

SimSensorTruth ReadSensorTruth(const std::string& path) {
  return ParseSensorTruth(io::ReadFileBytes(path), path);
}

}  // namespace lasercell::datasets
