#include "datasets/sim_config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"
#include "datasets/sim_profile.hpp"

namespace lasercell::datasets {

using yaml::Fields;

namespace {

std::string Num(double v) { return FormatDouble(v); }

template <typename Vec>
std::string List(const Vec& v) {
  std::string s = "[";
  for (int i = 0; i < static_cast<int>(v.size()); ++i) s += (i ? ", " : "") + Num(v[i]);
  return s + "]";
}

void CheckFinite(double v, const std::string& field) {
  if (!std::isfinite(v)) throw OptionError("SimConfig." + field + " must be finite");
}

void CheckAlbedo(double v, const std::string& field) {
  if (!(v >= 0 && v <= 1)) {
    throw OptionError("SimConfig.cell.albedo." + field + " must be in [0, 1] (got " +
                      std::to_string(v) + ")");
  }
}

void CheckRange(double v, double lo, double hi, const std::string& field) {
  if (!(v >= lo && v <= hi)) {
    throw OptionError(field + " must be in [" + Num(lo) + ", " + Num(hi) + "] (got " + Num(v) +
                      ")");
  }
}

}  // namespace

void TouchOptions::Check(const std::string& what) const {
  CheckRange(sigma_mm, 0.0, 10.0, what + ".sigma_mm");
  CheckRange(tool_length_mm, 0.0, 1000.0, what + ".tool_length_mm");
}

void PoseSweepOptions::Check(const std::string& what) const {
  if (poses < 1 || poses > 10000) {
    throw OptionError(what + ".poses must be in [1, 10000] (got " + std::to_string(poses) + ")");
  }
  CheckRange(min_tilt_deg, 0.0, 60.0, what + ".min_tilt_deg");
  CheckRange(max_tilt_deg, min_tilt_deg, 60.0, what + ".max_tilt_deg");
  CheckRange(max_roll_deg, 0.0, 180.0, what + ".max_roll_deg");
  if (!(sweep_length_mm > 0 && sweep_length_mm <= 1000)) {
    throw OptionError(what + ".sweep_length_mm must be in (0, 1000] (got " + Num(sweep_length_mm) +
                      ")");
  }
  if (profiles < 2 || profiles > 100000) {
    throw OptionError(what + ".profiles must be in [2, 100000] (got " + std::to_string(profiles) +
                      ")");
  }
  if (range_offsets_mm.empty()) {
    throw OptionError(what +
                      ".range_offsets_mm must list at least one offset (0: all sweeps at "
                      "the stand-off)");
  }
  for (double r : range_offsets_mm) CheckRange(r, -500.0, 500.0, what + ".range_offsets_mm");
}

void HandEyeImageOptions::Check(const std::string& what) const {
  if (images < 1 || images > 1000) {
    throw OptionError(what + ".images must be in [1, 1000] (got " + std::to_string(images) + ")");
  }
  if (!(distance_mm >= 100 && distance_mm <= 3000)) {
    throw OptionError(what + ".distance_mm must be in [100, 3000] (got " + Num(distance_mm) + ")");
  }
  CheckRange(min_tilt_deg, 0.0, 60.0, what + ".min_tilt_deg");
  CheckRange(max_tilt_deg, min_tilt_deg, 60.0, what + ".max_tilt_deg");
  CheckRange(max_roll_deg, 0.0, 180.0, what + ".max_roll_deg");
  CheckRange(board_height_mm, 0.0, 2000.0, what + ".board_height_mm");
  CheckRange(board_yaw_deg, -180.0, 180.0, what + ".board_yaw_deg");
}

namespace {

// Does the sensor see the targets? The laser's central ray points straight down during a
// linear sweep and crosses the optical axis at measuring_height_mm, so a horizontal target at
// height h lies at range (measuring_height - h) + |emitter -> crossing| along it.
void CheckTargetsInRange(const SimConfig& c) {
  const SensorModel model = MakeSensor(c.sensor);
  const double to_crossing = std::hypot(c.sensor.baseline_mm, c.sensor.standoff_mm);
  const auto check_range = [&](double height, const std::string& field, const char* target) {
    const double range = c.measuring_height_mm - height + to_crossing;
    const double far = std::min(model.central_range_mm[1], c.render.max_range_mm);
    if (!(range > model.central_range_mm[0] && range < far)) {
      std::ostringstream msg;
      msg << "SimConfig." << field << ": the sensor sees nothing of the " << target << " at height "
          << height << " mm: the laser meets it " << range
          << " mm from the emitter, outside the sensor's measuring range ["
          << model.central_range_mm[0] << ", " << far << "] mm along the laser; change " << field
          << " or sweep.measuring_height_mm (or sensor.baseline_mm/standoff_mm/camera, "
             "render.max_range_mm)";
      throw OptionError(msg.str());
    }
  };
  if (c.capture_planes) {
    for (std::size_t i = 0; i < c.plane_heights_mm.size(); ++i) {
      check_range(c.plane_heights_mm[i], "planes.heights_mm[" + std::to_string(i) + "]",
                  "white plane");
    }
  }
  if (c.capture_spheres) {
    const std::vector<Eigen::Vector3d> centers = c.spheres.CentersInCell();
    for (std::size_t i = 0; i < centers.size(); ++i) {
      check_range(centers[i].z() + c.spheres.radius_mm,
                  "spheres.stand_heights_mm[" + std::to_string(i) + "]", "sphere top");
    }
  }
  if (c.capture_seats || c.capture_trajectory) {
    check_range(kPalletHeightMm, "sweep.measuring_height_mm", "pallet deck under the seat");
    const double seat_height = c.seat_shape.thickness_mm + c.seat_shape.front_roll_mm +
                               c.seat_shape.crown_mm + c.seat_shape.side_lift_mm +
                               c.seat_shape.boss_height_mm;
    check_range(kPalletHeightMm + seat_height, "seats.shape.boss_height_mm",
                "top of the seat's boss");
  }
}

}  // namespace

void SimConfig::Check() const {
  sensor.Check("SimConfig.sensor");
  render.Check("SimConfig.render");
  timing.Check("SimConfig.timing");
  if (!mount_translation_mm.allFinite() || mount_translation_mm.norm() > 1000) {
    throw OptionError(
        "SimConfig.sensor.mount_translation_mm must be finite and within 1000 mm "
        "of the flange");
  }
  if (!mount_rotation_deg.allFinite() || mount_rotation_deg.norm() > 30) {
    throw OptionError("SimConfig.sensor.mount_rotation_deg must be finite, at most 30 deg");
  }
  for (int i = 0; i < 3; ++i) {
    CheckFinite(vision_base_mm[i], "cell.vision_base_mm");
    CheckFinite(handling_base_mm[i], "cell.handling_base_mm");
  }
  CheckFinite(vision_base_yaw_deg, "cell.vision_base_yaw_deg");
  CheckFinite(handling_base_yaw_deg, "cell.handling_base_yaw_deg");
  if (!(floor_size_mm >= 1500) || !std::isfinite(floor_size_mm)) {
    throw OptionError("SimConfig.cell.floor_size_mm must be >= 1500 (got " +
                      std::to_string(floor_size_mm) + ")");
  }
  CheckAlbedo(albedo.floor, "floor");
  CheckAlbedo(albedo.pallet, "pallet");
  CheckAlbedo(albedo.seat, "seat");
  CheckAlbedo(albedo.white_plane, "white_plane");
  CheckAlbedo(albedo.spheres, "spheres");
  CheckAlbedo(albedo.stands, "stands");
  CheckAlbedo(albedo.chessboard_light, "chessboard_light");
  CheckAlbedo(albedo.chessboard_dark, "chessboard_dark");
  if (joint_offsets_deg) {
    if (joint_offsets_deg->size() != 6) {
      throw OptionError("SimConfig.vision_robot.joint_offsets_deg must list 6 values (got " +
                        std::to_string(joint_offsets_deg->size()) + ")");
    }
    for (double v : *joint_offsets_deg) {
      if (!std::isfinite(v) || std::abs(v) > 10) {
        throw OptionError(
            "SimConfig.vision_robot.joint_offsets_deg values must be within +-10 deg");
      }
    }
  }
  for (const auto& [errors, name] : {std::pair{&dh_a_errors_mm, "dh_a_errors_mm"},
                                     std::pair{&dh_d_errors_mm, "dh_d_errors_mm"}}) {
    if (!*errors) continue;
    if ((*errors)->size() != 6) {
      throw OptionError(std::string("SimConfig.vision_robot.") + name +
                        " must list 6 values (got " + std::to_string((*errors)->size()) + ")");
    }
    for (double v : **errors) {
      if (!std::isfinite(v) || std::abs(v) > 10) {
        throw OptionError(std::string("SimConfig.vision_robot.") + name +
                          " values must be within +-10 mm");
      }
    }
  }
  if (!(dh_length_sigma_mm >= 0 && dh_length_sigma_mm <= 5)) {
    throw OptionError("SimConfig.vision_robot.dh_length_sigma_mm must be in [0, 5] (got " +
                      std::to_string(dh_length_sigma_mm) + ")");
  }
  if (!(joint_offset_sigma_deg >= 0 && joint_offset_sigma_deg <= 5)) {
    throw OptionError("SimConfig.vision_robot.joint_offset_sigma_deg must be in [0, 5] (got " +
                      std::to_string(joint_offset_sigma_deg) + ")");
  }
  CheckFinite(measuring_height_mm, "sweep.measuring_height_mm");
  if (!(sweep_length_mm > 0) || sweep_length_mm > 5000) {
    throw OptionError("SimConfig.sweep.length_mm must be in (0, 5000] (got " +
                      std::to_string(sweep_length_mm) + ")");
  }
  CheckFinite(sweep_center_xy_mm.x(), "sweep.center_xy_mm");
  CheckFinite(sweep_center_xy_mm.y(), "sweep.center_xy_mm");
  CheckFinite(sweep_direction_deg, "sweep.direction_deg");
  if (seat_count < 0 || seat_count > 100000 || (capture_seats && seat_count == 0)) {
    throw OptionError(
        "SimConfig.seats.count must be in [1, 100000] when captures.seats is true "
        "(got " +
        std::to_string(seat_count) + ")");
  }
  seat_placement.Check("SimConfig.seats");
  seat_shape.Check("SimConfig.seats.shape");
  seat_render.Check("SimConfig.seats.rendered");
  ParseSimProfile(profile);  // names the allowed profiles
  CheckRange(corner_sigma_px, 0.0, 5.0, "SimConfig.images.corner_sigma_px");
  if (capture_planes && plane_heights_mm.size() < 2) {
    throw OptionError(
        "SimConfig.planes.heights_mm must list at least 2 heights for the laser "
        "plane calibration (got " +
        std::to_string(plane_heights_mm.size()) + ")");
  }
  for (std::size_t i = 0; i < plane_heights_mm.size(); ++i) {
    if (!(plane_heights_mm[i] >= 20) || !std::isfinite(plane_heights_mm[i])) {
      throw OptionError("SimConfig.planes.heights_mm[" + std::to_string(i) +
                        "] must be >= 20 mm (got " + std::to_string(plane_heights_mm[i]) + ")");
    }
  }
  if (!(plane_size_mm.x() > 0) || !(plane_size_mm.y() > 0) || !plane_size_mm.allFinite()) {
    throw OptionError("SimConfig.planes.size_mm must be positive (got [" +
                      std::to_string(plane_size_mm.x()) + ", " + std::to_string(plane_size_mm.y()) +
                      "])");
  }
  spheres.Check("SimConfig.spheres");
  CheckRange(sphere_radius_tolerance_mm, 0.0, 0.1 * spheres.radius_mm,
             "SimConfig.spheres.radius_tolerance_mm");
  chessboard.Check("SimConfig.chessboard");
  images.Check("SimConfig.images");
  if (capture_chessboard_images && (chessboard_images < 1 || chessboard_images > 1000)) {
    throw OptionError(
        "SimConfig.chessboard.images must be in [1, 1000] when "
        "captures.chessboard_images is true (got " +
        std::to_string(chessboard_images) + ")");
  }
  if (!(arc_radius_mm >= 0 && arc_radius_mm <= 1000)) {
    throw OptionError("SimConfig.trajectory.arc_radius_mm must be in [0, 1000] (got " +
                      std::to_string(arc_radius_mm) + ")");
  }
  if (!(arc_angle_deg > 0 && arc_angle_deg <= 360)) {
    throw OptionError("SimConfig.trajectory.arc_angle_deg must be in (0, 360] (got " +
                      std::to_string(arc_angle_deg) + ")");
  }
  touches.Check("SimConfig.touches");
  eye_in_hand.Check("SimConfig.eye_in_hand");
  joint_poses.Check("SimConfig.joint_poses");
  hand_eye_images.Check("SimConfig.hand_eye_images");
  if ((capture_touches || capture_eye_in_hand || capture_joint_poses) &&
      spheres.stand_heights_mm.empty()) {
    throw OptionError(
        "SimConfig.spheres.stand_heights_mm must list at least one sphere for "
        "captures.touches/eye_in_hand/joint_poses");
  }
  if (arc_waypoints < 2 || arc_waypoints > 1000) {
    throw OptionError("SimConfig.trajectory.waypoints must be in [2, 1000] (got " +
                      std::to_string(arc_waypoints) + ")");
  }
  CheckTargetsInRange(*this);
}

namespace {

// The sensor, how it renders and when it exposes.
void ReadSensorSections(Fields& top, SimConfig& c) {
  {
    Fields s = top.Sub("sensor");
    {
      Fields cam = s.Sub("camera");
      cam.Read("width_px", &c.sensor.camera.width_px);
      cam.Read("height_px", &c.sensor.camera.height_px);
      cam.Read("fx_px", &c.sensor.camera.fx_px);
      cam.Read("fy_px", &c.sensor.camera.fy_px);
      cam.Read("cx_px", &c.sensor.camera.cx_px);
      cam.Read("cy_px", &c.sensor.camera.cy_px);
      cam.Read("distortion", &c.sensor.camera.distortion);
      cam.Done();
    }
    s.Read("baseline_mm", &c.sensor.baseline_mm);
    s.Read("standoff_mm", &c.sensor.standoff_mm);
    s.Read("fan_angle_deg", &c.sensor.fan_angle_deg);
    s.Read("mount_translation_mm", &c.mount_translation_mm);
    s.Read("mount_rotation_deg", &c.mount_rotation_deg);
    s.Done();
  }
  {
    Fields r = top.Sub("render");
    r.Read("fan_rays", &c.render.fan_rays);
    r.Read("max_range_mm", &c.render.max_range_mm);
    r.Read("intensity_gain", &c.render.intensity_gain);
    r.Read("reference_range_mm", &c.render.reference_range_mm);
    r.Read("min_intensity", &c.render.min_intensity);
    r.Read("max_view_angle_deg", &c.render.max_view_angle_deg);
    r.Read("sheet_thickness_mm", &c.render.sheet_thickness_mm);
    r.Read("min_width_px", &c.render.min_width_px);
    r.Read("row_sigma_px", &c.render.row_sigma_px);
    r.Read("intensity_sigma", &c.render.intensity_sigma);
    r.Read("dropout_probability", &c.render.dropout_probability);
    r.Read("speckle_sigma_px", &c.render.speckle_sigma_px);
    r.Read("speckle_correlation_px", &c.render.speckle_correlation_px);
    r.Read("speckle_intensity_sigma", &c.render.speckle_intensity_sigma);
    r.Read("occlusion_epsilon_mm", &c.render.occlusion_epsilon_mm);
    r.Read("reflection_probability", &c.render.reflection_probability);
    r.Read("reflection_intensity", &c.render.reflection_intensity);
    r.Read("reflective_objects", &c.render.reflective_objects);
    r.Done();
  }
  {
    Fields t = top.Sub("timing");
    t.Read("profiles", &c.timing.profiles);
    t.Read("rate_hz", &c.timing.rate_hz);
    t.Read("jitter_s", &c.timing.jitter_s);
    t.Read("timestamp_noise_s", &c.timing.timestamp_noise_s);
    t.Read("joint_noise_rad", &c.timing.joint_noise_rad);
    t.Read("start_ns", &c.timing.start_ns);
    t.Done();
  }
}

// The cell's layout and materials, and the vision robot's kinematic errors.
void ReadCellSections(Fields& top, SimConfig& c) {
  {
    Fields cell = top.Sub("cell");
    cell.Read("vision_base_mm", &c.vision_base_mm);
    cell.Read("vision_base_yaw_deg", &c.vision_base_yaw_deg);
    cell.Read("handling_base_mm", &c.handling_base_mm);
    cell.Read("handling_base_yaw_deg", &c.handling_base_yaw_deg);
    cell.Read("floor_size_mm", &c.floor_size_mm);
    Fields a = cell.Sub("albedo");
    a.Read("floor", &c.albedo.floor);
    a.Read("pallet", &c.albedo.pallet);
    a.Read("seat", &c.albedo.seat);
    a.Read("white_plane", &c.albedo.white_plane);
    a.Read("spheres", &c.albedo.spheres);
    a.Read("stands", &c.albedo.stands);
    a.Read("chessboard_light", &c.albedo.chessboard_light);
    a.Read("chessboard_dark", &c.albedo.chessboard_dark);
    a.Done();
    cell.Done();
  }
  {
    Fields r = top.Sub("vision_robot");
    std::vector<double> offsets;
    r.Read("joint_offsets_deg", &offsets);
    if (!offsets.empty()) c.joint_offsets_deg = offsets;
    r.Read("joint_offset_sigma_deg", &c.joint_offset_sigma_deg);
    std::vector<double> a_errors, d_errors;
    r.Read("dh_a_errors_mm", &a_errors);
    if (!a_errors.empty()) c.dh_a_errors_mm = a_errors;
    r.Read("dh_d_errors_mm", &d_errors);
    if (!d_errors.empty()) c.dh_d_errors_mm = d_errors;
    r.Read("dh_length_sigma_mm", &c.dh_length_sigma_mm);
    r.Done();
  }
}

// The linear sweep and what it scans: seats, white planes, spheres.
void ReadSceneSections(Fields& top, SimConfig& c) {
  {
    Fields s = top.Sub("sweep");
    s.Read("measuring_height_mm", &c.measuring_height_mm);
    s.Read("length_mm", &c.sweep_length_mm);
    s.Read("center_xy_mm", &c.sweep_center_xy_mm);
    s.Read("direction_deg", &c.sweep_direction_deg);
    s.Done();
  }
  {
    Fields s = top.Sub("seats");
    s.Read("count", &c.seat_count);
    s.Read("max_shift_mm", &c.seat_placement.max_shift_mm);
    s.Read("max_tilt_deg", &c.seat_placement.max_tilt_deg);
    s.Read("max_yaw_deg", &c.seat_placement.max_yaw_deg);
    Fields shape = s.Sub("shape");
    ChairSeatOptions& o = c.seat_shape;
    shape.Read("half_length_x_mm", &o.half_length_x_mm);
    shape.Read("half_width_y_mm", &o.half_width_y_mm);
    shape.Read("outline_exponent", &o.outline_exponent);
    shape.Read("crown_mm", &o.crown_mm);
    shape.Read("front_roll_mm", &o.front_roll_mm);
    shape.Read("side_lift_mm", &o.side_lift_mm);
    shape.Read("thickness_mm", &o.thickness_mm);
    shape.Read("boss_offset_x_mm", &o.boss_offset_x_mm);
    shape.Read("boss_radius_mm", &o.boss_radius_mm);
    shape.Read("boss_height_mm", &o.boss_height_mm);
    shape.Read("hole_diameter_mm", &o.hole_diameter_mm);
    shape.Read("angular_steps", &o.angular_steps);
    shape.Read("radial_steps", &o.radial_steps);
    shape.Done();
    Fields rendered = s.Sub("rendered");
    rendered.Read("angular_steps", &c.seat_render.angular_steps);
    rendered.Read("radial_steps", &c.seat_render.radial_steps);
    rendered.Read("warp_mm", &c.seat_render.warp_mm);
    rendered.Done();
    s.Done();
  }
  {
    Fields p = top.Sub("planes");
    p.Read("heights_mm", &c.plane_heights_mm);
    p.Read("size_mm", &c.plane_size_mm);
    p.Done();
  }
  {
    Fields s = top.Sub("spheres");
    s.Read("radius_mm", &c.spheres.radius_mm);
    s.Read("stand_heights_mm", &c.spheres.stand_heights_mm);
    s.Read("positions_xy_mm", &c.spheres.positions_xy_mm);
    s.Read("segments", &c.spheres.segments);
    s.Read("radius_tolerance_mm", &c.sphere_radius_tolerance_mm);
    s.Read("radius_errors_mm", &c.spheres.radius_errors_mm);
    s.Done();
  }
}

}  // namespace

SimConfig SimConfigFromYaml(const std::string& text, const std::string& name) {
  Fields top = Fields::Parse(text, name);
  top.ExpectFormat("lasercell.sim_config", kSimConfigVersion);
  // The named profile is the base; every other field changes it.
  std::string profile = "ideal";
  top.Read("profile", &profile);
  SimConfig c;
  try {
    c = SimConfigForProfile(profile);
  } catch (const OptionError& e) {
    throw OptionError(name + ": field 'profile': " + e.what());
  }
  top.Read("seed", &c.seed);
  ReadSensorSections(top, c);
  ReadCellSections(top, c);
  ReadSceneSections(top, c);
  {
    Fields t = top.Sub("trajectory");
    t.Read("arc_radius_mm", &c.arc_radius_mm);
    t.Read("arc_angle_deg", &c.arc_angle_deg);
    t.Read("waypoints", &c.arc_waypoints);
    t.Done();
  }
  {
    Fields b = top.Sub("chessboard");
    b.Read("images", &c.chessboard_images);
    Eigen::Vector2d squares(c.chessboard.SquaresX(), c.chessboard.SquaresY());
    b.Read("squares", &squares);
    if (squares.x() != std::round(squares.x()) || squares.y() != std::round(squares.y())) {
      throw OptionError(name + ": field 'chessboard.squares' must hold two integers");
    }
    // The file counts squares (as printed); the held BoardSpec counts inner corners.
    c.chessboard.board.cols = static_cast<int>(squares.x()) - 1;
    c.chessboard.board.rows = static_cast<int>(squares.y()) - 1;
    b.Read("square_mm", &c.chessboard.board.square_mm);
    b.Read("border_mm", &c.chessboard.border_mm);
    b.Done();
  }
  {
    Fields i = top.Sub("images");
    i.Read("exposure", &c.images.exposure);
    i.Read("ambient", &c.images.ambient);
    i.Read("background_albedo", &c.images.background_albedo);
    i.Read("blur_sigma_px", &c.images.blur_sigma_px);
    i.Read("noise_sigma", &c.images.noise_sigma);
    i.Read("vignetting", &c.images.vignetting);
    i.Read("edge_samples", &c.images.edge_samples);
    i.Read("corner_sigma_px", &c.corner_sigma_px);
    i.Done();
  }
  {
    Fields t = top.Sub("touches");
    t.Read("sigma_mm", &c.touches.sigma_mm);
    t.Read("tool_length_mm", &c.touches.tool_length_mm);
    t.Done();
  }
  for (auto [key, options] :
       {std::pair{"eye_in_hand", &c.eye_in_hand}, std::pair{"joint_poses", &c.joint_poses}}) {
    Fields p = top.Sub(key);
    p.Read("poses", &options->poses);
    p.Read("min_tilt_deg", &options->min_tilt_deg);
    p.Read("max_tilt_deg", &options->max_tilt_deg);
    p.Read("max_roll_deg", &options->max_roll_deg);
    p.Read("sweep_length_mm", &options->sweep_length_mm);
    p.Read("profiles", &options->profiles);
    p.Read("range_offsets_mm", &options->range_offsets_mm);
    p.Done();
  }
  {
    Fields h = top.Sub("hand_eye_images");
    h.Read("images", &c.hand_eye_images.images);
    h.Read("distance_mm", &c.hand_eye_images.distance_mm);
    h.Read("min_tilt_deg", &c.hand_eye_images.min_tilt_deg);
    h.Read("max_tilt_deg", &c.hand_eye_images.max_tilt_deg);
    h.Read("max_roll_deg", &c.hand_eye_images.max_roll_deg);
    h.Read("board_height_mm", &c.hand_eye_images.board_height_mm);
    h.Read("board_yaw_deg", &c.hand_eye_images.board_yaw_deg);
    h.Done();
  }
  {
    Fields k = top.Sub("captures");
    k.Read("planes", &c.capture_planes);
    k.Read("spheres", &c.capture_spheres);
    k.Read("seats", &c.capture_seats);
    k.Read("trajectory", &c.capture_trajectory);
    k.Read("chessboard_images", &c.capture_chessboard_images);
    k.Read("laser_line_images", &c.capture_laser_line_images);
    k.Read("meshes", &c.write_meshes);
    k.Read("touches", &c.capture_touches);
    k.Read("eye_in_hand", &c.capture_eye_in_hand);
    k.Read("joint_poses", &c.capture_joint_poses);
    k.Read("hand_eye_images", &c.capture_hand_eye_images);
    k.Done();
  }
  top.Done();
  return c;
}

SimConfig LoadSimConfig(const std::string& path) {
  return SimConfigFromYaml(io::ReadFileBytes(path), path);
}

std::string SimConfigToYaml(const SimConfig& c) {
  std::ostringstream o;
  const auto& cam = c.sensor.camera;
  const auto& r = c.render;
  const auto& s = c.seat_shape;
  o << "format: lasercell.sim_config\nversion: " << kSimConfigVersion << "\n";
  o << "profile: " << c.profile << "\n";
  o << "seed: " << c.seed << "\n";
  o << "sensor:\n  camera: {width_px: " << cam.width_px << ", height_px: " << cam.height_px
    << ", fx_px: " << Num(cam.fx_px) << ", fy_px: " << Num(cam.fy_px)
    << ", cx_px: " << Num(cam.cx_px) << ", cy_px: " << Num(cam.cy_px)
    << ", distortion: " << List(cam.distortion) << "}\n";
  o << "  baseline_mm: " << Num(c.sensor.baseline_mm)
    << "\n  standoff_mm: " << Num(c.sensor.standoff_mm)
    << "\n  fan_angle_deg: " << Num(c.sensor.fan_angle_deg)
    << "\n  mount_translation_mm: " << List(c.mount_translation_mm)
    << "\n  mount_rotation_deg: " << List(c.mount_rotation_deg) << "\n";
  o << "render: {fan_rays: " << r.fan_rays << ", max_range_mm: " << Num(r.max_range_mm)
    << ", intensity_gain: " << Num(r.intensity_gain)
    << ", reference_range_mm: " << Num(r.reference_range_mm)
    << ", min_intensity: " << Num(r.min_intensity)
    << ", max_view_angle_deg: " << Num(r.max_view_angle_deg)
    << ", sheet_thickness_mm: " << Num(r.sheet_thickness_mm)
    << ", min_width_px: " << Num(r.min_width_px) << ", row_sigma_px: " << Num(r.row_sigma_px)
    << ", intensity_sigma: " << Num(r.intensity_sigma)
    << ", dropout_probability: " << Num(r.dropout_probability)
    << ", speckle_sigma_px: " << Num(r.speckle_sigma_px)
    << ", speckle_correlation_px: " << Num(r.speckle_correlation_px)
    << ", speckle_intensity_sigma: " << Num(r.speckle_intensity_sigma)
    << ", occlusion_epsilon_mm: " << Num(r.occlusion_epsilon_mm)
    << ", reflection_probability: " << Num(r.reflection_probability)
    << ", reflection_intensity: " << Num(r.reflection_intensity) << ", reflective_objects: [";
  for (std::size_t i = 0; i < r.reflective_objects.size(); ++i) {
    o << (i ? ", " : "") << r.reflective_objects[i];
  }
  o << "]}\n";
  o << "timing: {profiles: " << c.timing.profiles << ", rate_hz: " << Num(c.timing.rate_hz)
    << ", jitter_s: " << Num(c.timing.jitter_s)
    << ", timestamp_noise_s: " << Num(c.timing.timestamp_noise_s)
    << ", joint_noise_rad: " << Num(c.timing.joint_noise_rad) << ", start_ns: " << c.timing.start_ns
    << "}\n";
  o << "cell:\n  vision_base_mm: " << List(c.vision_base_mm)
    << "\n  vision_base_yaw_deg: " << Num(c.vision_base_yaw_deg)
    << "\n  handling_base_mm: " << List(c.handling_base_mm)
    << "\n  handling_base_yaw_deg: " << Num(c.handling_base_yaw_deg)
    << "\n  floor_size_mm: " << Num(c.floor_size_mm)
    << "\n  albedo: {floor: " << Num(c.albedo.floor) << ", pallet: " << Num(c.albedo.pallet)
    << ", seat: " << Num(c.albedo.seat) << ", white_plane: " << Num(c.albedo.white_plane)
    << ", spheres: " << Num(c.albedo.spheres) << ", stands: " << Num(c.albedo.stands)
    << ", chessboard_light: " << Num(c.albedo.chessboard_light)
    << ", chessboard_dark: " << Num(c.albedo.chessboard_dark) << "}\n";
  o << "vision_robot:\n";
  if (c.joint_offsets_deg) o << "  joint_offsets_deg: " << List(*c.joint_offsets_deg) << "\n";
  o << "  joint_offset_sigma_deg: " << Num(c.joint_offset_sigma_deg) << "\n";
  if (c.dh_a_errors_mm) o << "  dh_a_errors_mm: " << List(*c.dh_a_errors_mm) << "\n";
  if (c.dh_d_errors_mm) o << "  dh_d_errors_mm: " << List(*c.dh_d_errors_mm) << "\n";
  o << "  dh_length_sigma_mm: " << Num(c.dh_length_sigma_mm) << "\n";
  o << "sweep: {measuring_height_mm: " << Num(c.measuring_height_mm)
    << ", length_mm: " << Num(c.sweep_length_mm) << ", center_xy_mm: " << List(c.sweep_center_xy_mm)
    << ", direction_deg: " << Num(c.sweep_direction_deg) << "}\n";
  o << "seats:\n  count: " << c.seat_count
    << "\n  max_shift_mm: " << Num(c.seat_placement.max_shift_mm)
    << "\n  max_tilt_deg: " << Num(c.seat_placement.max_tilt_deg)
    << "\n  max_yaw_deg: " << Num(c.seat_placement.max_yaw_deg)
    << "\n  shape: {half_length_x_mm: " << Num(s.half_length_x_mm)
    << ", half_width_y_mm: " << Num(s.half_width_y_mm)
    << ", outline_exponent: " << Num(s.outline_exponent) << ", crown_mm: " << Num(s.crown_mm)
    << ", front_roll_mm: " << Num(s.front_roll_mm) << ", side_lift_mm: " << Num(s.side_lift_mm)
    << ", thickness_mm: " << Num(s.thickness_mm)
    << ", boss_offset_x_mm: " << Num(s.boss_offset_x_mm)
    << ", boss_radius_mm: " << Num(s.boss_radius_mm)
    << ", boss_height_mm: " << Num(s.boss_height_mm)
    << ", hole_diameter_mm: " << Num(s.hole_diameter_mm) << ", angular_steps: " << s.angular_steps
    << ", radial_steps: " << s.radial_steps << "}\n";
  o << "  rendered: {angular_steps: " << c.seat_render.angular_steps
    << ", radial_steps: " << c.seat_render.radial_steps
    << ", warp_mm: " << Num(c.seat_render.warp_mm) << "}\n";
  o << "planes: {heights_mm: " << List(c.plane_heights_mm) << ", size_mm: " << List(c.plane_size_mm)
    << "}\n";
  o << "spheres:\n  radius_mm: " << Num(c.spheres.radius_mm)
    << "\n  stand_heights_mm: " << List(c.spheres.stand_heights_mm) << "\n  positions_xy_mm: [";
  for (std::size_t i = 0; i < c.spheres.positions_xy_mm.size(); ++i) {
    o << (i ? ", " : "") << List(c.spheres.positions_xy_mm[i]);
  }
  o << "]\n  segments: " << c.spheres.segments
    << "\n  radius_tolerance_mm: " << Num(c.sphere_radius_tolerance_mm) << "\n";
  if (!c.spheres.radius_errors_mm.empty()) {
    o << "  radius_errors_mm: " << List(c.spheres.radius_errors_mm) << "\n";
  }
  o << "trajectory: {arc_radius_mm: " << Num(c.arc_radius_mm)
    << ", arc_angle_deg: " << Num(c.arc_angle_deg) << ", waypoints: " << c.arc_waypoints << "}\n";
  const auto b = [](bool v) { return v ? "true" : "false"; };
  o << "chessboard: {images: " << c.chessboard_images << ", squares: [" << c.chessboard.SquaresX()
    << ", " << c.chessboard.SquaresY() << "], square_mm: " << Num(c.chessboard.board.square_mm)
    << ", border_mm: " << Num(c.chessboard.border_mm) << "}\n";
  o << "images: {exposure: " << Num(c.images.exposure) << ", ambient: " << Num(c.images.ambient)
    << ", background_albedo: " << Num(c.images.background_albedo)
    << ", blur_sigma_px: " << Num(c.images.blur_sigma_px)
    << ", noise_sigma: " << Num(c.images.noise_sigma) << ", vignetting: " << b(c.images.vignetting)
    << ", edge_samples: " << c.images.edge_samples
    << ", corner_sigma_px: " << Num(c.corner_sigma_px) << "}\n";
  o << "touches: {sigma_mm: " << Num(c.touches.sigma_mm)
    << ", tool_length_mm: " << Num(c.touches.tool_length_mm) << "}\n";
  for (auto [key, p] :
       {std::pair{"eye_in_hand", &c.eye_in_hand}, std::pair{"joint_poses", &c.joint_poses}}) {
    o << key << ": {poses: " << p->poses << ", min_tilt_deg: " << Num(p->min_tilt_deg)
      << ", max_tilt_deg: " << Num(p->max_tilt_deg) << ", max_roll_deg: " << Num(p->max_roll_deg)
      << ", sweep_length_mm: " << Num(p->sweep_length_mm) << ", profiles: " << p->profiles
      << ", range_offsets_mm: " << List(p->range_offsets_mm) << "}\n";
  }
  const HandEyeImageOptions& h = c.hand_eye_images;
  o << "hand_eye_images: {images: " << h.images << ", distance_mm: " << Num(h.distance_mm)
    << ", min_tilt_deg: " << Num(h.min_tilt_deg) << ", max_tilt_deg: " << Num(h.max_tilt_deg)
    << ", max_roll_deg: " << Num(h.max_roll_deg) << ", board_height_mm: " << Num(h.board_height_mm)
    << ", board_yaw_deg: " << Num(h.board_yaw_deg) << "}\n";
  o << "captures: {planes: " << b(c.capture_planes) << ", spheres: " << b(c.capture_spheres)
    << ", seats: " << b(c.capture_seats) << ", trajectory: " << b(c.capture_trajectory)
    << ", chessboard_images: " << b(c.capture_chessboard_images)
    << ", laser_line_images: " << b(c.capture_laser_line_images)
    << ", meshes: " << b(c.write_meshes) << ", touches: " << b(c.capture_touches)
    << ", eye_in_hand: " << b(c.capture_eye_in_hand)
    << ", joint_poses: " << b(c.capture_joint_poses)
    << ", hand_eye_images: " << b(c.capture_hand_eye_images) << "}\n";
  return o.str();
}

}  // namespace lasercell::datasets
