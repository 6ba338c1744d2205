#include "datasets/calibration_captures.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "datasets/rng.hpp"
#include "datasets/robots.hpp"

namespace lasercell::datasets {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kHalfPi = std::numbers::pi / 2;
// Fewest noise-free columns on the aimed-at sphere in the middle exposure of a pose sweep.
constexpr std::size_t kMinSphereColumns = 30;
// Draws per requested pose before giving up.
constexpr int kAttemptsPerPose = 60;

std::string Num(double v) { return FormatDouble(v); }

std::string List(const std::vector<double>& q) {
  std::string s = "[";
  for (std::size_t j = 0; j < q.size(); ++j) {
    if (j > 0) s += ", ";
    s += Num(q[j]);
  }
  s += "]";
  return s;
}

std::string Vec(const Eigen::Vector3d& v) { return List({v.x(), v.y(), v.z()}); }

void WrapJoints(std::vector<double>& q) {
  for (double& v : q) v = std::remainder(v, 2 * std::numbers::pi);
}

// UR5 postures to start the IK from (shoulder, elbow, wrist choices), as in MakeArcTrajectory.
std::vector<std::vector<double>> Ur5Seeds() {
  std::vector<std::vector<double>> seeds;
  for (double q1 : {0.0, kHalfPi, -kHalfPi, 2 * kHalfPi}) {
    for (double q3 : {kHalfPi, -kHalfPi}) {
      for (double q5 : {-kHalfPi, kHalfPi}) seeds.push_back({q1, -kHalfPi, q3, -kHalfPi, q5, 0.0});
    }
  }
  return seeds;
}

}  // namespace

Eigen::Isometry3d PointingTool(const TouchOptions& options) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(0, 0, options.tool_length_mm);
  return t;
}

Eigen::Isometry3d TrueCellFromSensor(const CellTruth& truth, const std::vector<double>& q) {
  return truth.layout.cell_from_vision_base * truth.true_vision_robot.BaseFromFlange(q) *
         truth.vision_flange_from_sensor;
}

std::vector<Touch> SimulateTouches(const SimConfig& config, const CellTruth& truth,
                                   std::uint64_t seed) {
  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  const Eigen::Isometry3d tip_from_flange = PointingTool(config.touches).inverse();
  const Eigen::Vector3d hb_in_cell = truth.layout.cell_from_handling_base.translation();
  Rng rng(seed);
  std::vector<Touch> touches;
  const std::vector<Eigen::Vector3d> centers = config.spheres.CentersInCell();
  for (std::size_t i = 0; i < centers.size(); ++i) {
    Touch t;
    t.sphere = static_cast<int>(i);
    const Eigen::Vector3d top_cell = centers[i] + Eigen::Vector3d(0, 0, truth.spheres.RadiusOf(i));
    t.true_top_in_handling_base = hb_from_cell * top_cell;
    Eigen::Vector3d noise;
    for (int k = 0; k < 3; ++k) noise[k] = rng.Normal(0.0, config.touches.sigma_mm);
    t.measured_in_handling_base = t.true_top_in_handling_base + noise;
    // The controller reports the joints of the touched (measured) point: IK with the tool
    // pointing down, tilted towards the robot as far as needed to reach.
    Eigen::Vector2d u = (hb_in_cell - top_cell).head<2>();
    u = u.norm() > 1e-9 ? Eigen::Vector2d(u.normalized()) : Eigen::Vector2d(1, 0);
    const Eigen::Vector3d axis(-u.y(), u.x(), 0.0);  // tilts the tool axis away from the robot
    const Eigen::Matrix3d down = Eigen::Vector3d(1, -1, -1).asDiagonal();
    const Eigen::Vector3d measured_cell =
        truth.layout.cell_from_handling_base * t.measured_in_handling_base;
    for (double tilt_deg : {0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0}) {
      Eigen::Isometry3d cell_from_tip = Eigen::Isometry3d::Identity();
      cell_from_tip.linear() =
          Eigen::AngleAxisd(tilt_deg * kDegToRad, axis).toRotationMatrix() * down;
      cell_from_tip.translation() = measured_cell;
      const Eigen::Isometry3d hb_from_flange = hb_from_cell * cell_from_tip * tip_from_flange;
      const Eigen::Vector3d p = hb_from_flange.translation();
      const double q1 = std::atan2(p.y(), p.x());
      for (const std::vector<double>& s : {std::vector<double>{q1, 0.0, 0.0, 0.0, -kHalfPi, 0.0},
                                           std::vector<double>{q1, 0.5, -0.3, 0.0, -1.0, 0.0},
                                           std::vector<double>{q1, 0.0, 0.0, 0.0, kHalfPi, 0.0},
                                           std::vector<double>{q1, 0.8, 0.3, 0.0, -1.2, 0.0},
                                           std::vector<double>{q1, 1.2, -0.2, 0.0, -0.5, 0.0},
                                           std::vector<double>{q1, 1.0, 0.0, 0.0, 0.0, 0.0}}) {
        auto q = SolveIk(truth.handling_robot, hb_from_flange, s);
        if (q) {
          WrapJoints(*q);
          t.joints_rad = *q;
          t.tool_tilt_deg = tilt_deg;
          break;
        }
      }
      if (t.joints_rad) break;
    }
    touches.push_back(t);
  }
  return touches;
}

SweepTiming PoseSweepTiming(const SimConfig& config, const PoseSweepOptions& options) {
  SweepTiming timing = config.timing;
  timing.profiles = options.profiles;
  return timing;
}

std::vector<PoseSweep> PlanPoseSweeps(const SimConfig& config, const CellTruth& truth,
                                      const PoseSweepOptions& options, std::uint64_t seed,
                                      const std::string& what) {
  const Scene scene = MakeSphereScene(truth.layout, truth.spheres);
  LaserRenderOptions exact = config.render;
  exact.row_sigma_px = exact.intensity_sigma = exact.dropout_probability = 0;
  const LaserRenderer renderer(scene, truth.sensor, exact);
  const std::vector<Eigen::Vector3d> centers = config.spheres.CentersInCell();
  const Eigen::Isometry3d base_from_cell = truth.layout.cell_from_vision_base.inverse();
  const Eigen::Isometry3d sensor_from_flange = truth.vision_flange_from_sensor.inverse();
  const Eigen::Matrix3d looking_down =
      SensorLookingDown(truth.sensor.laser, Eigen::Vector3d::UnitX());
  const SweepTiming timing = PoseSweepTiming(config, options);
  const double duration = (timing.profiles - 1) / timing.rate_hz;
  const std::vector<std::vector<double>> seeds = Ur5Seeds();
  const double standoff = config.sensor.standoff_mm;
  Rng rng(seed);
  std::vector<PoseSweep> plans;
  for (int i = 0; i < options.poses; ++i) {
    const int sphere = i % static_cast<int>(centers.size());
    const std::int32_t sphere_object = scene.Find("sphere_" + std::to_string(sphere));
    bool found = false;
    for (int attempt = 0; attempt < kAttemptsPerPose && !found; ++attempt) {
      PoseSweep p;
      p.sphere = sphere;
      p.range_offset_mm =
          options.range_offsets_mm[static_cast<std::size_t>(i) % options.range_offsets_mm.size()];
      // Azimuths stratified over the circle so the tilt axes spread; tilt and roll uniform.
      p.azimuth_deg = 360.0 * (i + rng.Uniform()) / options.poses - 180.0;
      p.tilt_deg = rng.Uniform(options.min_tilt_deg, options.max_tilt_deg);
      p.roll_deg = rng.Uniform(-options.max_roll_deg, options.max_roll_deg);
      const double az = p.azimuth_deg * kDegToRad;
      const Eigen::Vector3d tilt_axis(std::cos(az), std::sin(az), 0.0);
      const Eigen::Matrix3d r_cell_sensor =
          (Eigen::AngleAxisd(p.tilt_deg * kDegToRad, tilt_axis) *
           Eigen::AngleAxisd(p.roll_deg * kDegToRad, Eigen::Vector3d::UnitZ()))
              .toRotationMatrix() *
          looking_down;
      const Eigen::Vector3d optical_axis = r_cell_sensor.col(2);
      // The laser crosses the optical axis half a radius in front of the sphere centre.
      const Eigen::Vector3d crossing =
          centers[sphere] - 0.5 * config.spheres.radius_mm * optical_axis;
      const Eigen::Vector3d direction = r_cell_sensor * truth.sensor.laser.normal_in_sensor;
      // Backing off along the laser's central ray keeps the sphere in the laser plane.
      const Eigen::Vector3d back_off =
          -p.range_offset_mm * (r_cell_sensor * truth.sensor.laser.center_in_sensor);
      std::vector<Eigen::Isometry3d> waypoints;
      for (double s : {-0.5, 0.0, 0.5}) {
        Eigen::Isometry3d cell_from_sensor = Eigen::Isometry3d::Identity();
        cell_from_sensor.linear() = r_cell_sensor;
        cell_from_sensor.translation() =
            crossing - standoff * optical_axis + back_off + s * options.sweep_length_mm * direction;
        waypoints.push_back(cell_from_sensor);
      }
      // Middle waypoint first, from the postures in an order that varies with the pose (so the
      // joint-offset set visits several arm configurations), then the ends from the middle.
      std::optional<std::vector<double>> mid;
      for (std::size_t k = 0; k < seeds.size() && !mid; ++k) {
        mid =
            SolveIk(truth.nominal_vision_robot, base_from_cell * waypoints[1] * sensor_from_flange,
                    seeds[(k + static_cast<std::size_t>(i)) % seeds.size()]);
      }
      if (!mid) continue;
      WrapJoints(*mid);
      const auto start = SolveIk(truth.nominal_vision_robot,
                                 base_from_cell * waypoints[0] * sensor_from_flange, *mid);
      const auto end = SolveIk(truth.nominal_vision_robot,
                               base_from_cell * waypoints[2] * sensor_from_flange, *mid);
      if (!start || !end) continue;
      bool continuous = true;
      for (int j = 0; j < 6; ++j) {
        continuous = continuous && std::abs((*start)[j] - (*mid)[j]) < 0.5 &&
                     std::abs((*end)[j] - (*mid)[j]) < 0.5;
      }
      if (!continuous) continue;
      p.trajectory.times_s = {0.0, 0.5 * duration, duration};
      p.trajectory.joints_rad = {*start, *mid, *end};
      p.commanded_cell_from_sensor = waypoints;
      const ExposureTruth seen = renderer.RenderExact(TrueCellFromSensor(truth, *mid));
      for (std::int32_t o : seen.object) p.sphere_columns_at_middle += (o == sphere_object);
      if (p.sphere_columns_at_middle < kMinSphereColumns) continue;
      plans.push_back(std::move(p));
      found = true;
    }
    if (!found) {
      throw OptionError(what + ": pose " + std::to_string(i) + " of " +
                        std::to_string(options.poses) + " (sphere " + std::to_string(sphere) +
                        "): no drawn pose is reachable by the vision robot and sees the sphere; "
                        "change " +
                        what +
                        ".max_tilt_deg/max_roll_deg/sweep_length_mm, "
                        "SimConfig.spheres.* or SimConfig.cell.vision_base_mm");
    }
  }
  return plans;
}

SweepResult RenderPoseSweep(const LaserRenderer& renderer, const CellTruth& truth,
                            const PoseSweep& sweep, const SweepTiming& timing, std::uint64_t seed,
                            int threads) {
  return RenderSweep(
      renderer,
      [&](double t) {
        SensorState s;
        s.joints_rad = sweep.trajectory.At(t);
        s.scene_from_sensor = TrueCellFromSensor(truth, s.joints_rad);
        return s;
      },
      timing, seed, 6, "vision_robot", threads);
}

std::string TouchesRecordYaml(const SimConfig& config, const std::vector<Touch>& touches) {
  std::ostringstream o;
  o << "format: lasercell.touches\nversion: 1\n"
    << "# Pointing-tool touches of the sphere tops by the handling robot, as its controller\n"
    << "# reports them: tool-tip position in handling_base (mm) and the joints (rad) of the\n"
    << "# touch (null when not recorded). tool_tip = FK(joints) * handling_flange_from_tool_tip.\n"
    << "robot: handling_robot\nframe: handling_base\n"
    << "handling_flange_from_tool_tip: " << PoseToFileNotation(PointingTool(config.touches))
    << "\nstated_sigma_mm: " << Num(config.touches.sigma_mm)
    << "\nsphere_radius_mm: " << Num(config.spheres.radius_mm) << "\n";
  // The spheres' grade: what their maker states, not the radii drawn within it.
  if (config.sphere_radius_tolerance_mm > 0) {
    o << "sphere_radius_tolerance_mm: " << Num(config.sphere_radius_tolerance_mm) << "\n";
  }
  o << "touches:\n";
  for (const Touch& t : touches) {
    o << "  - sphere: " << t.sphere
      << "\n    point_in_handling_base: " << Vec(t.measured_in_handling_base)
      << "\n    joints_rad: " << (t.joints_rad ? List(*t.joints_rad) : std::string("null")) << "\n";
  }
  return o.str();
}

std::string TouchesTruthYaml(const SimConfig& config, const CellTruth& truth,
                             const std::vector<Touch>& touches) {
  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  const std::vector<Eigen::Vector3d> centers = config.spheres.CentersInCell();
  std::ostringstream o;
  o << "format: lasercell.sim_touches_truth\nversion: 1\n"
    << "# True sphere centres and tops for records/touches.yaml (same order), mm.\n"
    << "sphere_radius_mm: " << Num(config.spheres.radius_mm)
    << "\ntouch_sigma_mm: " << Num(config.touches.sigma_mm) << "\ntouches:\n";
  for (const Touch& t : touches) {
    o << "  - sphere: " << t.sphere
      << "\n    sphere_center_in_handling_base: " << Vec(hb_from_cell * centers[t.sphere])
      << "\n    sphere_center_in_cell: " << Vec(centers[t.sphere])
      << "\n    true_sphere_radius_mm: " << Num(truth.spheres.RadiusOf(t.sphere))
      << "\n    true_top_in_handling_base: " << Vec(t.true_top_in_handling_base)
      << "\n    touch_error_mm: " << Vec(t.measured_in_handling_base - t.true_top_in_handling_base)
      << "\n    tool_tilt_deg: " << Num(t.tool_tilt_deg) << "\n";
  }
  return o.str();
}

std::string PoseSweepTruthYaml(const SimConfig& config, const CellTruth& truth,
                               const PoseSweep& p) {
  const Eigen::Vector3d center = config.spheres.CentersInCell()[p.sphere];
  std::ostringstream o;
  // The sweep block comes last: the exposure truth the caller appends belongs inside it.
  o << "    sphere: " << p.sphere << "\n    sphere_radius_mm: " << Num(config.spheres.radius_mm)
    << "\n    true_sphere_radius_mm: " << Num(truth.spheres.RadiusOf(p.sphere))
    << "\n    sphere_center_in_cell: " << Vec(center) << "\n    sphere_center_in_vision_base: "
    << Vec(truth.layout.cell_from_vision_base.inverse() * center)
    << "\n    sphere_columns_at_middle: " << p.sphere_columns_at_middle << "\n";
  o << "    sweep:\n      type: joints\n      robot: vision_robot\n"
    << "      interpolation: linear in joint space between waypoints (nominal IK)\n"
    << "      t0_ns: " << config.timing.start_ns
    << "\n      waypoint_times_s: " << List(p.trajectory.times_s) << "\n      waypoints_rad:\n";
  for (const auto& q : p.trajectory.joints_rad) o << "        - " << List(q) << "\n";
  o << "      commanded_cell_from_sensor:\n";
  for (const auto& pose : p.commanded_cell_from_sensor) {
    o << "        - " << PoseToFileNotation(pose) << "\n";
  }
  o << "      true_cell_from_sensor:\n";
  for (const auto& q : p.trajectory.joints_rad) {
    o << "        - " << PoseToFileNotation(TrueCellFromSensor(truth, q)) << "\n";
  }
  o << "      range_offset_mm: " << Num(p.range_offset_mm) << "\n";
  o << "      tilt_deg: " << Num(p.tilt_deg) << "\n      azimuth_deg: " << Num(p.azimuth_deg)
    << "\n      roll_deg: " << Num(p.roll_deg) << "\n";
  return o.str();
}

HandEyeImageSet PlanHandEyeImages(const SimConfig& config, const CellTruth& truth,
                                  const ChessboardTarget& target, std::uint64_t seed) {
  const HandEyeImageOptions& options = config.hand_eye_images;
  const std::string what = "SimConfig.hand_eye_images";
  options.Check(what);
  target.Check();
  HandEyeImageSet set;
  const Eigen::Vector3d board_center(0.5 * target.SquaresX() * target.board.square_mm,
                                     0.5 * target.SquaresY() * target.board.square_mm, 0.0);
  set.cell_from_board.linear() =
      Eigen::AngleAxisd(options.board_yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  set.cell_from_board.translation() =
      Eigen::Vector3d(config.sweep_center_xy_mm.x(), config.sweep_center_xy_mm.y(),
                      options.board_height_mm) -
      set.cell_from_board.linear() * board_center;
  const Eigen::Vector3d center_in_cell = set.cell_from_board * board_center;
  const Eigen::Isometry3d base_from_cell = truth.layout.cell_from_vision_base.inverse();
  const Eigen::Isometry3d sensor_from_flange = truth.vision_flange_from_sensor.inverse();
  const Eigen::Matrix3d looking_down =
      SensorLookingDown(truth.sensor.laser, Eigen::Vector3d::UnitX());
  const std::vector<std::vector<double>> seeds = Ur5Seeds();
  const std::vector<Eigen::Vector3d> corners = target.CornersInTarget();
  const calib::CameraModel& camera = truth.sensor.camera;
  const double margin_px = 25.0;
  Rng rng(seed);
  for (int i = 0; i < options.images; ++i) {
    bool found = false;
    for (int attempt = 0; attempt < kAttemptsPerPose && !found; ++attempt) {
      HandEyeImage im;
      im.azimuth_deg = 360.0 * (i + rng.Uniform()) / options.images - 180.0;
      im.tilt_deg = rng.Uniform(options.min_tilt_deg, options.max_tilt_deg);
      im.roll_deg = rng.Uniform(-options.max_roll_deg, options.max_roll_deg);
      const double az = im.azimuth_deg * kDegToRad;
      const Eigen::Vector3d tilt_axis(std::cos(az), std::sin(az), 0.0);
      im.commanded_cell_from_camera.linear() =
          (Eigen::AngleAxisd(im.tilt_deg * kDegToRad, tilt_axis) *
           Eigen::AngleAxisd(im.roll_deg * kDegToRad, Eigen::Vector3d::UnitZ()))
              .toRotationMatrix() *
          looking_down;
      im.commanded_cell_from_camera.translation() =
          center_in_cell - options.distance_mm * im.commanded_cell_from_camera.linear().col(2);
      const Eigen::Isometry3d base_from_flange =
          base_from_cell * im.commanded_cell_from_camera * sensor_from_flange;
      std::optional<std::vector<double>> q;
      for (std::size_t k = 0; k < seeds.size() && !q; ++k) {
        q = SolveIk(truth.nominal_vision_robot, base_from_flange,
                    seeds[(k + static_cast<std::size_t>(i)) % seeds.size()]);
      }
      if (!q) continue;
      WrapJoints(*q);
      im.joints_rad = *q;
      im.true_cell_from_camera = TrueCellFromSensor(truth, *q);
      im.camera_from_board = im.true_cell_from_camera.inverse() * set.cell_from_board;
      bool inside = true;
      for (const Eigen::Vector3d& p : corners) {
        const Eigen::Vector3d pc = im.camera_from_board * p;
        const auto px = pc.z() > 0 ? ProjectInView(camera, pc) : std::nullopt;
        if (!px || px->x() < margin_px || px->y() < margin_px ||
            px->x() > camera.width_px() - 1 - margin_px ||
            px->y() > camera.height_px() - 1 - margin_px) {
          inside = false;
          break;
        }
        im.corners_px.push_back(*px);
      }
      if (!inside) continue;
      set.images.push_back(std::move(im));
      found = true;
    }
    if (!found) {
      throw OptionError(what + ": image " + std::to_string(i) + " of " +
                        std::to_string(options.images) +
                        ": no drawn pose is reachable by the vision robot and shows the whole "
                        "board; change " +
                        what +
                        ".distance_mm/max_tilt_deg/board_height_mm or "
                        "SimConfig.sweep.center_xy_mm");
    }
  }
  return set;
}

std::string HandEyeImageFile(std::size_t i) {
  char name[48];
  std::snprintf(name, sizeof(name), "images/hand_eye_%03zu.png", i);
  return name;
}

std::string HandEyeImagesRecordYaml(const ChessboardTarget& target, const HandEyeImageSet& set) {
  std::ostringstream o;
  o << "format: lasercell.hand_eye_images\nversion: 1\n"
    << "# Chessboard images taken by the sensor camera on the vision robot, with the joints (rad)\n"
    << "# the controller reports for each. The board lies still in the cell. Board frame and\n"
    << "# corner order as truth/chessboard.yaml.\nrobot: vision_robot\n"
    << "board: {squares: [" << target.SquaresX() << ", " << target.SquaresY()
    << "], inner_corners: [" << target.board.cols << ", " << target.board.rows
    << "], square_mm: " << Num(target.board.square_mm) << "}\nimages:\n";
  for (std::size_t i = 0; i < set.images.size(); ++i) {
    o << "  - file: " << HandEyeImageFile(i)
      << "\n    joints_rad: " << List(set.images[i].joints_rad) << "\n";
  }
  return o.str();
}

std::string HandEyeImagesTruthYaml(const CellTruth& truth, const HandEyeImageSet& set) {
  std::ostringstream o;
  o << "format: lasercell.sim_hand_eye_images_truth\nversion: 1\n"
    << "# Truth of records/hand_eye_images.yaml (same order). Camera = sensor frame; pixel\n"
    << "# centre of the top-left pixel at (0, 0). true_cell_from_camera = cell_from_vision_base *\n"
    << "# TRUE robot FK(joints) * vision_flange_from_sensor; commanded = what the nominal model\n"
    << "# promises at the same joints.\n"
    << "cell_from_board: " << PoseToFileNotation(set.cell_from_board)
    << "\nvision_base_from_board: "
    << PoseToFileNotation(truth.layout.cell_from_vision_base.inverse() * set.cell_from_board)
    << "\nimages:\n";
  for (std::size_t i = 0; i < set.images.size(); ++i) {
    const HandEyeImage& im = set.images[i];
    o << "  - file: " << HandEyeImageFile(i)
      << "\n    true_cell_from_camera: " << PoseToFileNotation(im.true_cell_from_camera)
      << "\n    commanded_cell_from_camera: " << PoseToFileNotation(im.commanded_cell_from_camera)
      << "\n    camera_from_board: " << PoseToFileNotation(im.camera_from_board)
      << "\n    tilt_deg: " << Num(im.tilt_deg) << "\n    azimuth_deg: " << Num(im.azimuth_deg)
      << "\n    roll_deg: " << Num(im.roll_deg) << "\n    corners_px: [";
    for (std::size_t k = 0; k < im.corners_px.size(); ++k) {
      o << (k ? ", " : "") << "[" << Num(im.corners_px[k].x()) << ", " << Num(im.corners_px[k].y())
        << "]";
    }
    o << "]\n";
  }
  return o.str();
}

}  // namespace lasercell::datasets
