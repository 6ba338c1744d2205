#include "datasets/simulate.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

#include "calib/laser_plane_heights_record.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/io/mesh_io.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/parallel.hpp"
#include "core/se3.hpp"
#include "datasets/calibration_captures.hpp"
#include "datasets/camera_images.hpp"
#include "datasets/chair_parts.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/rng.hpp"
#include "datasets/robots.hpp"
#include "datasets/simulate_records.hpp"
#include "localize/part.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/sphere_sweeps.hpp"

namespace lasercell::datasets {

namespace {

using sim_text::Num;
using sim_text::Pose;
using sim_text::Vec;

constexpr double kDegToRad = std::numbers::pi / 180.0;
// Random streams (rng.hpp StreamSeed): one per purpose, so adding a capture never changes the
// others.
constexpr std::uint64_t kRobotStream = 0x0B07;
constexpr std::uint64_t kDhLengthStream = 0x0B08;
constexpr std::uint64_t kSphereRadiusStream = 0x0B09;
constexpr std::uint64_t kPlaneStream = 0x1000;
constexpr std::uint64_t kSphereStream = 0x2000;
constexpr std::uint64_t kTrajectoryStream = 0x3000;
constexpr std::uint64_t kChessboardStream = 0x4000;
constexpr std::uint64_t kLaserImageStream = 0x5000;
constexpr std::uint64_t kTouchStream = 0x6000;
constexpr std::uint64_t kEyeInHandPlanStream = 0x7000;
constexpr std::uint64_t kJointPosePlanStream = 0x8000;
constexpr std::uint64_t kHandEyeImageStream = 0x9000;  // plan; + 1 + i: image noise
constexpr std::uint64_t kSeatStream = 0x10000;
constexpr std::uint64_t kEyeInHandStream = 0x1000000;  // + pose index
constexpr std::uint64_t kJointPoseStream = 0x2000000;  // + pose index

const char* const kTool = "lasercell simulator " LASERCELL_VERSION;

Eigen::Isometry3d YawPose(const Eigen::Vector3d& t, double yaw_deg) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.translation() = t;
  return p;
}

StaticEdge Edge(const std::string& parent, const std::string& child,
                const Eigen::Isometry3d& parent_from_child, const std::string& note) {
  StaticEdge e;
  e.parent = parent;
  e.child = child;
  e.SetParentFromChild(parent_from_child);
  e.provenance.tool = kTool;
  e.provenance.residual_summary = note;
  return e;
}

// Pose of the sensor looking down with the laser crossing the optical axis at `crossing` and
// the laser plane normal (sweep direction) along `direction`.
Eigen::Isometry3d LookingDownAt(const SensorModel& sensor, double standoff_mm,
                                const Eigen::Vector3d& crossing, const Eigen::Vector3d& direction) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = SensorLookingDown(sensor.laser, direction);
  pose.translation() = crossing - pose.linear() * Eigen::Vector3d(0, 0, standoff_mm);
  return pose;
}

// Output folder with its subfolders, and the list of files written.
class Output {
 public:
  explicit Output(const std::string& dir) : dir_(dir) {
    std::error_code ec;
    for (const char* sub : {"", "profiles", "truth", "models", "images", "records"}) {
      std::filesystem::create_directories(std::filesystem::path(dir) / sub, ec);
      if (ec) throw FileError(dir, "cannot create the output folder: " + ec.message());
    }
  }
  void Write(const std::string& relative, std::string_view bytes) {
    io::WriteFileAtomically(Path(relative), bytes);
    files_.push_back(relative);
  }
  // models/<name>.ply and models/<name>.stl.
  void WriteMesh(const std::string& name, const TriangleMesh& mesh) {
    io::WritePlyMesh(Path("models/" + name + ".ply"), mesh);
    files_.push_back("models/" + name + ".ply");
    io::WriteStlMesh(Path("models/" + name + ".stl"), mesh);
    files_.push_back("models/" + name + ".stl");
  }
  std::string Path(const std::string& relative) const {
    return (std::filesystem::path(dir_) / relative).string();
  }
  std::vector<std::string>& files() { return files_; }

 private:
  std::string dir_;
  std::vector<std::string> files_;
};

// Renders one linear or robot sweep, writes its profile file, and fails loudly when the
// sensor saw nothing.
struct SweepJob {
  std::string name;
  std::string kind;
  std::string target_fields;  // config fields to blame when nothing is seen
};

CaptureReport WriteSweep(const SweepJob& job, const SweepResult& result, const SimConfig& config,
                         Output& out) {
  if (result.valid_peaks == 0) {
    throw OptionError("capture '" + job.name + "' (" + job.kind +
                      "): the sensor sees nothing of the target in any of its " +
                      std::to_string(result.profiles.profiles.size()) + " profiles; check " +
                      job.target_fields + ", SimConfig.sweep.* and SimConfig.render.min_intensity");
  }
  triangulation::ProfileSet set = result.profiles;
  set.header.metadata = "format: lasercell.capture\ncapture: " + job.name + "\nkind: " + job.kind +
                        "\nsimulator: \"" + kTool + "\"\nseed: " + std::to_string(config.seed) +
                        "\n";
  CaptureReport r;
  r.name = job.name;
  r.kind = job.kind;
  r.profiles_file = "profiles/" + job.name + ".lcp";
  r.profiles = set.profiles.size();
  r.valid_peaks = result.valid_peaks;
  out.Write(r.profiles_file, triangulation::EncodeProfiles(set));
  return r;
}

// "[r_0, r_1, ...]": every sphere's true radius, mm.
std::string TrueRadiiList(const SphereTargets& spheres) {
  std::string s;
  for (std::size_t i = 0; i < spheres.stand_heights_mm.size(); ++i) {
    s += (i ? ", " : "") + Num(spheres.RadiusOf(i));
  }
  return "[" + s + "]";
}

TriangleMesh SphereTargetsMesh(const CellTruth& truth) {
  const Scene scene = MakeSphereScene(truth.layout, truth.spheres);
  MeshPart all;
  for (const SceneObject& o : scene.objects()) {
    if (o.name != "floor" && o.name != "pallet") all.Append(o.geometry);
  }
  return all.mesh;
}

// Seat placements and their scenes.
std::vector<SeatCapture> DrawSeats(const SimConfig& config, const CellTruth& truth, int count) {
  std::vector<SeatCapture> seats;
  for (int i = 0; i < count; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "seat_%03d", i);
    seats.push_back({name, DrawSeatPlacement(config.seat_placement, truth.seat, config.seed, i)});
  }
  return seats;
}

// Renders and writes the seat scenes; appends their truth to `captures_yaml`.
void RunSeats(const SimConfig& config, const CellTruth& truth,
              const std::vector<SeatCapture>& seats, const LinearSweep& sweep,
              const Eigen::Isometry3d& hb_from_cell, Output& out, SimulationReport& report,
              std::string& captures_yaml, const ProgressCallback& progress, int threads) {
  for (std::size_t i = 0; i < seats.size(); ++i) {
    const Scene scene = MakeSeatScene(truth.layout, truth.seat, seats[i].placement.cell_from_part);
    const LaserRenderer renderer(scene, truth.sensor, config.render);
    const SweepResult result = RenderSweep(
        renderer,
        [&](double t) {
          return SensorState{sweep.At(t), {}};
        },
        config.timing, StreamSeed(config.seed, kSeatStream + i), 0, "", threads);
    const CaptureReport r = WriteSweep(
        {seats[i].name, "seat", "SimConfig.seats.* (placement " + std::to_string(i) + ")"}, result,
        config, out);
    report.captures.push_back(r);
    captures_yaml += CaptureHeaderYaml(r) + LinearSweepTruthYaml(sweep, hb_from_cell, config) +
                     ExposureTimesTruthYaml(result, config) +
                     SeatTruthYaml(seats[i], truth, hb_from_cell);
    ReportProgress(progress, "seats", static_cast<double>(i + 1) / seats.size());
  }
}

ChessboardTarget TargetOf(const SimConfig& config) {
  ChessboardTarget target = config.chessboard;
  target.dark_albedo = config.albedo.chessboard_dark;
  target.light_albedo = config.albedo.chessboard_light;
  return target;
}

void RunChessboardImages(const SimConfig& config, const CellTruth& truth, Output& out,
                         int threads) {
  const ChessboardTarget target = TargetOf(config);
  const calib::CameraModel& camera = truth.sensor.camera;
  const ImageRenderer renderer(camera);
  const std::vector<Eigen::Isometry3d> poses = DrawChessboardPoses(
      target, camera, config.chessboard_images, StreamSeed(config.seed, kChessboardStream));
  std::vector<std::string> pngs(poses.size());
  // One image per index (its own noise stream): the same files for any thread count.
  ParallelForChunks(threads, poses.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      pngs[i] = EncodePng(renderer.RenderChessboard(
          target, poses[i], config.images, StreamSeed(config.seed, kChessboardStream + 1 + i)));
    }
  });
  std::ostringstream o;
  o << "format: lasercell.sim_chessboard\nversion: 1\n"
    << "# Board frame: pattern in its xy plane, square (i, j) at [i s, (i+1) s] x [j s, (j+1) s],\n"
    << "# dark when i + j is even; inner corner (i, j) at ((i+1) s, (j+1) s, 0), listed row by "
       "row\n"
    << "# along x (OpenCV order). Pixel coordinates: centre of the top-left pixel is (0, 0).\n"
    << "board: {squares: [" << target.SquaresX() << ", " << target.SquaresY()
    << "], inner_corners: [" << target.board.cols << ", " << target.board.rows
    << "], square_mm: " << Num(target.board.square_mm) << ", border_mm: " << Num(target.border_mm)
    << ", dark_albedo: " << Num(target.dark_albedo)
    << ", light_albedo: " << Num(target.light_albedo) << "}\nimages:\n";
  for (std::size_t i = 0; i < poses.size(); ++i) {
    char name[48];
    std::snprintf(name, sizeof(name), "images/chessboard_%03zu.png", i);
    out.Write(name, pngs[i]);
    o << "  - file: " << name << "\n    camera_from_board: " << Pose(poses[i])
      << "\n    corners_px: [";
    bool first = true;
    for (const Eigen::Vector3d& p : target.CornersInTarget()) {
      const auto q = ProjectInView(camera, poses[i] * p);
      o << (first ? "" : ", ") << "[" << Num(q->x()) << ", " << Num(q->y()) << "]";
      first = false;
    }
    o << "]\n";
  }
  out.Write("truth/chessboard.yaml", o.str());
}

void RunHandEyeImages(const SimConfig& config, const CellTruth& truth, Output& out, int threads) {
  const ChessboardTarget target = TargetOf(config);
  const HandEyeImageSet set =
      PlanHandEyeImages(config, truth, target, StreamSeed(config.seed, kHandEyeImageStream));
  const ImageRenderer renderer(truth.sensor.camera);
  std::vector<std::string> pngs(set.images.size());
  ParallelForChunks(threads, set.images.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      pngs[i] = EncodePng(renderer.RenderChessboard(
          target, set.images[i].camera_from_board, config.images,
          StreamSeed(config.seed, kHandEyeImageStream + 1 + static_cast<std::uint64_t>(i))));
    }
  });
  for (std::size_t i = 0; i < pngs.size(); ++i) out.Write(HandEyeImageFile(i), pngs[i]);
  out.Write("records/hand_eye_images.yaml", HandEyeImagesRecordYaml(target, set));
  out.Write("truth/hand_eye_images.yaml", HandEyeImagesTruthYaml(truth, set));
}

std::string RowList(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    s += (i ? ", " : "") + (std::isnan(v[i]) ? std::string(".nan") : Num(v[i]));
  }
  return s + "]";
}

void RunLaserLineImages(const SimConfig& config, const CellTruth& truth, const LinearSweep& sweep,
                        Output& out) {
  const double mid = 0.5 * (config.timing.profiles - 1) / config.timing.rate_hz;
  const Eigen::Isometry3d pose = sweep.At(mid);
  // The stripe on the white plane (first height) and on a chessboard lying flat under the
  // sweep's midpoint, pattern up.
  const ChessboardTarget target = TargetOf(config);
  const double s = target.board.square_mm;
  Eigen::Isometry3d cell_from_board = Eigen::Isometry3d::Identity();  // target frame
  cell_from_board.translation() =
      Eigen::Vector3d(config.sweep_center_xy_mm.x() - target.SquaresX() * s / 2,
                      config.sweep_center_xy_mm.y() - target.SquaresY() * s / 2,
                      config.plane_heights_mm.empty() ? 150.0 : config.plane_heights_mm.front());
  struct Case {
    std::string name;
    Scene scene;
  };
  std::vector<Case> cases;
  cases.push_back(
      {"laser_line_plane",
       MakePlaneScene(truth.layout, cell_from_board.translation().z(), config.plane_size_mm)});
  cases.push_back(
      {"laser_line_chessboard", MakeChessboardScene(truth.layout, cell_from_board,
                                                    {target.SquaresX(), target.SquaresY()}, s)});
  const ImageRenderer images(truth.sensor.camera);
  std::ostringstream o;
  o << "format: lasercell.sim_laser_lines\nversion: 1\n"
    << "# Exact (noise-free) peak row per image column of each raw laser-line image; .nan where\n"
    << "# the column has no peak. Stripe profile: Gaussian of FWHM width_px, peak 255 * "
       "intensity.\n"
    << "images:\n";
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const LaserRenderer renderer(cases[k].scene, truth.sensor, config.render);
    const ExposureTruth exposure = renderer.RenderExact(pose);
    const std::string file = "images/" + cases[k].name + ".png";
    out.Write(file, EncodePng(images.RenderLaserLine(
                        exposure, config.images, StreamSeed(config.seed, kLaserImageStream + k))));
    o << "  - file: " << file << "\n    cell_from_sensor: " << Pose(pose)
      << "\n    rows_px: " << RowList(exposure.row_px)
      << "\n    width_px: " << RowList(exposure.width_px)
      << "\n    intensity: " << RowList(exposure.intensity) << "\n";
  }
  out.Write("truth/laser_lines.yaml", o.str());
}

// Pointing-tool touches: records/touches.yaml (what the cell records) and truth/touches.yaml.
void RunTouches(const SimConfig& config, const CellTruth& truth, Output& out) {
  const std::vector<Touch> touches =
      SimulateTouches(config, truth, StreamSeed(config.seed, kTouchStream));
  out.Write("records/touches.yaml", TouchesRecordYaml(config, touches));
  out.Write("truth/touches.yaml", TouchesTruthYaml(config, truth, touches));
}

// One set of pose sweeps (eye_in_hand or joint_poses): profiles, captures.yaml entries, and
// the set's list in records/sphere_sweeps.yaml.
void RunPoseSweeps(const SimConfig& config, const CellTruth& truth, const PoseSweepOptions& options,
                   const std::vector<PoseSweep>& plans, const std::string& set,
                   const char* name_format, std::uint64_t render_stream, Output& out,
                   SimulationReport& report, std::string& captures_yaml,
                   triangulation::SphereSweepList& records, const ProgressCallback& progress,
                   int threads) {
  const Scene scene = MakeSphereScene(truth.layout, truth.spheres);
  const LaserRenderer renderer(scene, truth.sensor, config.render);
  const SweepTiming timing = PoseSweepTiming(config, options);
  records.sets.push_back({set, {}});
  for (std::size_t i = 0; i < plans.size(); ++i) {
    char name[48];
    std::snprintf(name, sizeof(name), name_format, static_cast<int>(i));
    const SweepResult result = RenderPoseSweep(renderer, truth, plans[i], timing,
                                               StreamSeed(config.seed, render_stream + i), threads);
    const CaptureReport r =
        WriteSweep({name, set + "_sphere", "SimConfig." + set + ".* and SimConfig.spheres.*"},
                   result, config, out);
    report.captures.push_back(r);
    records.sets.back().sweeps.push_back({r.profiles_file, plans[i].sphere});
    captures_yaml += CaptureHeaderYaml(r) + PoseSweepTruthYaml(config, truth, plans[i]) +
                     ExposureTimesTruthYaml(result, config);
    ReportProgress(progress, set, static_cast<double>(i + 1) / plans.size());
  }
}

void WriteCommonTruth(const SimConfig& config, const CellTruth& truth,
                      const std::vector<SeatCapture>& seats, Output& out) {
  FrameGraph graph = truth.Graph();
  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  for (const SeatCapture& s : seats) {
    graph.SetStaticEdge(Edge("handling_base", s.name, hb_from_cell * s.placement.cell_from_part,
                             "simulated ground truth (part pose)"));
  }
  out.Write("truth/cell.yaml", FrameGraphToYaml(graph));
  out.Write("truth/camera.cameramodel", MrcalCameraModelText(config.sensor.camera));
  out.Write("truth/sensor.yaml", SensorTruthYaml(truth, config));
  out.Write("truth/robots.yaml", RobotsTruthYaml(truth));
  out.Write("truth/sim_config.yaml", SimConfigToYaml(config));
  if (config.write_meshes) {
    out.WriteMesh("seat", truth.seat_cad.part.mesh);
    out.Write("models/seat.part.yaml",
              localize::PartFileYaml(SeatPartDefinition(truth.seat_cad, &truth.seat)));
    out.WriteMesh("pallet", MakePallet().mesh);
    out.WriteMesh("sphere_targets", SphereTargetsMesh(truth));
  }
}

// The white plane at every planes.heights_mm: profiles and captures.yaml entries.
void RunPlanes(const SimConfig& config, const CellTruth& truth, const LinearSweep& sweep,
               const Eigen::Isometry3d& hb_from_cell, Output& out, SimulationReport& report,
               std::string& captures_yaml, const ProgressCallback& progress, int threads) {
  for (std::size_t i = 0; i < config.plane_heights_mm.size(); ++i) {
    const double h = config.plane_heights_mm[i];
    const Scene scene = MakePlaneScene(truth.layout, h, config.plane_size_mm);
    const LaserRenderer renderer(scene, truth.sensor, config.render);
    const SweepResult result = RenderSweep(
        renderer,
        [&](double t) {
          return SensorState{sweep.At(t), {}};
        },
        config.timing, StreamSeed(config.seed, kPlaneStream + i), 0, "", threads);
    const std::string name = "plane_" + std::to_string(i);
    const CaptureReport r =
        WriteSweep({name, "white_plane", "SimConfig.planes.heights_mm[" + std::to_string(i) + "]"},
                   result, config, out);
    report.captures.push_back(r);
    const Eigen::Vector3d n_hb = hb_from_cell.linear() * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d p_hb = hb_from_cell * Eigen::Vector3d(0, 0, h);
    captures_yaml += CaptureHeaderYaml(r) + LinearSweepTruthYaml(sweep, hb_from_cell, config) +
                     ExposureTimesTruthYaml(result, config) +
                     "    plane_height_in_cell_mm: " + Num(h) +
                     "\n    plane_in_handling_base: {normal: " + Vec(n_hb) +
                     ", d_mm: " + Num(-n_hb.dot(p_hb)) + "}\n";
    ReportProgress(progress, "white planes",
                   static_cast<double>(i + 1) / config.plane_heights_mm.size());
  }
}

// The sphere targets: profiles and the captures.yaml entry.
void RunSpheres(const SimConfig& config, const CellTruth& truth, const LinearSweep& sweep,
                const Eigen::Isometry3d& hb_from_cell, Output& out, SimulationReport& report,
                std::string& captures_yaml, const ProgressCallback& progress, int threads) {
  const Scene scene = MakeSphereScene(truth.layout, truth.spheres);
  const LaserRenderer renderer(scene, truth.sensor, config.render);
  const SweepResult result = RenderSweep(
      renderer,
      [&](double t) {
        return SensorState{sweep.At(t), {}};
      },
      config.timing, StreamSeed(config.seed, kSphereStream), 0, "", threads);
  const CaptureReport r =
      WriteSweep({"spheres", "spheres", "SimConfig.spheres.*"}, result, config, out);
  report.captures.push_back(r);
  std::string centers_cell, centers_hb;
  for (const Eigen::Vector3d& c : config.spheres.CentersInCell()) {
    centers_cell += (centers_cell.empty() ? "" : ", ") + Vec(c);
    centers_hb += (centers_hb.empty() ? "" : ", ") + Vec(hb_from_cell * c);
  }
  captures_yaml += CaptureHeaderYaml(r) + LinearSweepTruthYaml(sweep, hb_from_cell, config) +
                   ExposureTimesTruthYaml(result, config) +
                   "    sphere_radius_mm: " + Num(config.spheres.radius_mm) +
                   "\n    true_sphere_radii_mm: " + TrueRadiiList(truth.spheres) +
                   "\n    sphere_centers_in_cell: [" + centers_cell +
                   "]\n    sphere_centers_in_handling_base: [" + centers_hb + "]\n";
  ReportProgress(progress, "spheres", 1.0);
}

// The robot sweep over the first seat: profiles (joints in each) and the captures.yaml entry.
void RunTrajectory(const SimConfig& config, const CellTruth& truth,
                   const JointTrajectory& trajectory, const SeatCapture& seat,
                   const Eigen::Isometry3d& hb_from_cell, Output& out, SimulationReport& report,
                   std::string& captures_yaml, const ProgressCallback& progress, int threads) {
  const Scene scene = MakeSeatScene(truth.layout, truth.seat, seat.placement.cell_from_part);
  const LaserRenderer renderer(scene, truth.sensor, config.render);
  const Eigen::Isometry3d& cell_from_base = truth.layout.cell_from_vision_base;
  const auto state_at = [&](double t) {
    SensorState s;
    s.joints_rad = trajectory.At(t);
    s.scene_from_sensor = cell_from_base * truth.true_vision_robot.BaseFromFlange(s.joints_rad) *
                          truth.vision_flange_from_sensor;
    return s;
  };
  const SweepResult result =
      RenderSweep(renderer, state_at, config.timing, StreamSeed(config.seed, kTrajectoryStream), 6,
                  "vision_robot", threads);
  const std::string name = "trajectory_" + seat.name;
  const CaptureReport r =
      WriteSweep({name, "seat_trajectory", "SimConfig.trajectory.* and SimConfig.seats.*"}, result,
                 config, out);
  report.captures.push_back(r);
  std::ostringstream o;
  o << "    sweep:\n      type: joints\n      robot: vision_robot\n"
    << "      interpolation: linear in joint space between waypoints\n"
    << "      t0_ns: " << config.timing.start_ns << "\n      waypoint_times_s: [";
  for (std::size_t k = 0; k < trajectory.times_s.size(); ++k) {
    o << (k ? ", " : "") << Num(trajectory.times_s[k]);
  }
  o << "]\n      waypoints_rad:\n";
  for (const auto& q : trajectory.joints_rad) {
    o << "        - [";
    for (std::size_t j = 0; j < q.size(); ++j) o << (j ? ", " : "") << Num(q[j]);
    o << "]\n";
  }
  captures_yaml += CaptureHeaderYaml(r) + o.str() + ExposureTimesTruthYaml(result, config) +
                   SeatTruthYaml({seat.name, seat.placement}, truth, hb_from_cell);
  ReportProgress(progress, "robot trajectory", 1.0);
}

}  // namespace

FrameGraph CellTruth::Graph() const {
  FrameGraph g;
  g.SetRobot("vision_robot", true_vision_robot);
  g.SetRobot("handling_robot", handling_robot);
  g.SetStaticEdge(
      Edge("cell", "vision_base", layout.cell_from_vision_base, "simulated ground truth"));
  g.SetStaticEdge(
      Edge("cell", "handling_base", layout.cell_from_handling_base, "simulated ground truth"));
  g.SetDynamicEdge({"vision_base", "vision_flange", "vision_robot"});
  g.SetDynamicEdge({"handling_base", "handling_flange", "handling_robot"});
  g.SetStaticEdge(
      Edge("vision_flange", "sensor", vision_flange_from_sensor, "simulated ground truth"));
  g.SetStaticEdge(Edge("sensor", "camera", Eigen::Isometry3d::Identity(),
                       "the simulated sensor frame is the camera frame"));
  return g;
}

CellTruth MakeCellTruth(const SimConfig& config) {
  config.Check();
  CellTruth t;
  t.layout.cell_from_vision_base = YawPose(config.vision_base_mm, config.vision_base_yaw_deg);
  t.layout.cell_from_handling_base = YawPose(config.handling_base_mm, config.handling_base_yaw_deg);
  t.layout.floor_size_mm = config.floor_size_mm;
  t.layout.albedo = config.albedo;
  t.sensor = MakeSensor(config.sensor);
  // Nominal mount: with the flange pointing down (flange z = -cell z, flange x = cell x) the
  // sensor looks down with its laser plane normal along cell x; then the configured extra
  // rotation (in the flange frame) and the camera centre's position.
  const Eigen::Matrix3d cell_from_flange_down = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Matrix3d flange_from_sensor_nominal =
      cell_from_flange_down.transpose() *
      SensorLookingDown(t.sensor.laser, Eigen::Vector3d::UnitX());
  t.vision_flange_from_sensor.linear() =
      QuaternionFromRotationVector(config.mount_rotation_deg * kDegToRad).toRotationMatrix() *
      flange_from_sensor_nominal;
  t.vision_flange_from_sensor.translation() = config.mount_translation_mm;
  t.nominal_vision_robot = NominalUr5();
  if (config.joint_offsets_deg) {
    for (double d : *config.joint_offsets_deg) t.joint_offsets_rad.push_back(d * kDegToRad);
  } else {
    Rng rng(StreamSeed(config.seed, kRobotStream));
    for (int i = 0; i < 6; ++i) {
      t.joint_offsets_rad.push_back(rng.Normal(0.0, config.joint_offset_sigma_deg * kDegToRad));
    }
  }
  // DH length errors draw from a stream of their own, so enabling them leaves the joint offsets
  // (and every other draw) of a seed unchanged.
  Rng dh_rng(StreamSeed(config.seed, kDhLengthStream));
  const auto lengths = [&](const std::optional<std::vector<double>>& explicit_mm) {
    if (explicit_mm) return *explicit_mm;
    std::vector<double> e(6, 0.0);
    if (config.dh_length_sigma_mm > 0) {
      for (double& v : e) v = dh_rng.Normal(0.0, config.dh_length_sigma_mm);
    }
    return e;
  };
  t.dh_a_errors_mm = lengths(config.dh_a_errors_mm);
  t.dh_d_errors_mm = lengths(config.dh_d_errors_mm);
  t.true_vision_robot = ApplyRobotErrors(t.nominal_vision_robot,
                                         {t.joint_offsets_rad, t.dh_a_errors_mm, t.dh_d_errors_mm});
  t.handling_robot = ApproximateNachiSc15f();
  t.seat = MakeRenderedChairSeat(config.seat_shape, config.seat_render);
  t.seat_cad = MakeChairSeat(config.seat_shape);
  t.spheres = config.spheres;
  if (t.spheres.radius_errors_mm.empty() && config.sphere_radius_tolerance_mm > 0) {
    Rng radius_rng(StreamSeed(config.seed, kSphereRadiusStream));
    for (std::size_t i = 0; i < t.spheres.stand_heights_mm.size(); ++i) {
      t.spheres.radius_errors_mm.push_back(radius_rng.Uniform(-config.sphere_radius_tolerance_mm,
                                                              config.sphere_radius_tolerance_mm));
    }
  }
  return t;
}

LinearSweep MakeLinearSweep(const SimConfig& config, const SensorModel& sensor) {
  const double a = config.sweep_direction_deg * kDegToRad;
  const Eigen::Vector3d dir(std::cos(a), std::sin(a), 0.0);
  const Eigen::Vector3d center(config.sweep_center_xy_mm.x(), config.sweep_center_xy_mm.y(),
                               config.measuring_height_mm);
  const double duration = (config.timing.profiles - 1) / config.timing.rate_hz;
  LinearSweep s;
  s.cell_from_sensor_start = LookingDownAt(sensor, config.sensor.standoff_mm,
                                           center - 0.5 * config.sweep_length_mm * dir, dir);
  s.velocity_mm_s = duration > 0 ? Eigen::Vector3d(dir * config.sweep_length_mm / duration)
                                 : Eigen::Vector3d::Zero();
  return s;
}

std::vector<double> JointTrajectory::At(double t) const {
  LASERCELL_CHECK(!times_s.empty() && times_s.size() == joints_rad.size(), "trajectory shape");
  if (t <= times_s.front()) return joints_rad.front();
  if (t >= times_s.back()) return joints_rad.back();
  std::size_t k = 1;
  while (times_s[k] < t) ++k;
  const double w = (t - times_s[k - 1]) / (times_s[k] - times_s[k - 1]);
  std::vector<double> q(joints_rad[k].size());
  for (std::size_t j = 0; j < q.size(); ++j) {
    q[j] = (1 - w) * joints_rad[k - 1][j] + w * joints_rad[k][j];
  }
  return q;
}

JointTrajectory MakeArcTrajectory(const SimConfig& config, const CellTruth& truth) {
  const int n = config.arc_waypoints;
  const double duration = (config.timing.profiles - 1) / config.timing.rate_hz;
  const double arc = config.arc_angle_deg * kDegToRad;
  const double phi0 = -std::numbers::pi / 2 - arc / 2;
  const Eigen::Isometry3d base_from_cell = truth.layout.cell_from_vision_base.inverse();
  const Eigen::Isometry3d sensor_from_flange = truth.vision_flange_from_sensor.inverse();
  JointTrajectory traj;
  std::vector<double> seed;
  for (int k = 0; k < n; ++k) {
    const double s = static_cast<double>(k) / (n - 1);
    const double phi = phi0 + arc * s;
    const Eigen::Vector3d crossing(
        config.sweep_center_xy_mm.x() + config.arc_radius_mm * std::cos(phi),
        config.sweep_center_xy_mm.y() + config.arc_radius_mm * std::sin(phi),
        config.measuring_height_mm);
    const Eigen::Vector3d tangent(-std::sin(phi), std::cos(phi), 0.0);
    const Eigen::Isometry3d cell_from_sensor =
        LookingDownAt(truth.sensor, config.sensor.standoff_mm, crossing, tangent);
    const Eigen::Isometry3d base_from_flange =
        base_from_cell * cell_from_sensor * sensor_from_flange;
    std::optional<std::vector<double>> q;
    if (k == 0) {
      // Deterministic multi-start: the first converged of a fixed list of UR5 postures.
      constexpr double h = std::numbers::pi / 2;
      for (double q1 : {0.0, h, -h, 2 * h}) {
        for (double q3 : {h, -h}) {
          for (double q5 : {-h, h}) {
            q = SolveIk(truth.nominal_vision_robot, base_from_flange, {q1, -h, q3, -h, q5, 0.0});
            if (q) break;
          }
          if (q) break;
        }
        if (q) break;
      }
    } else {
      q = SolveIk(truth.nominal_vision_robot, base_from_flange, seed);
    }
    if (q && k == 0) {
      // Start inside the UR5's +-2 pi joint ranges with room both ways; later waypoints follow
      // continuously from here.
      for (double& v : *q) v = std::remainder(v, 2 * std::numbers::pi);
    }
    if (!q) {
      throw OptionError(
          "SimConfig.trajectory: the vision robot (UR5 at cell.vision_base_mm) "
          "cannot reach arc waypoint " +
          std::to_string(k) + " of " + std::to_string(n) +
          "; change trajectory.arc_radius_mm, sweep.measuring_height_mm, "
          "sweep.center_xy_mm or cell.vision_base_mm");
    }
    seed = *q;
    traj.times_s.push_back(duration * s);
    traj.joints_rad.push_back(*q);
  }
  return traj;
}

std::string SimulationReport::Summary() const {
  std::size_t peaks = 0;
  for (const CaptureReport& c : captures) peaks += c.valid_peaks;
  std::ostringstream o;
  o.precision(3);
  o << captures.size() << " captures, " << static_cast<double>(peaks) / 1e6 << "M peaks, "
    << files.size() << " files in " << seconds << " s";
  return o.str();
}

SimulationReport SimulateCell(const SimConfig& config, const std::string& out_dir,
                              const ProgressCallback& progress, int threads) {
  const auto start = std::chrono::steady_clock::now();
  const CellTruth truth = MakeCellTruth(config);
  Output out(out_dir);
  SimulationReport report;
  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  const LinearSweep sweep = MakeLinearSweep(config, truth.sensor);
  std::string captures_yaml = CapturesPreambleYaml(config, truth);

  // Solve the robot trajectory first: an unreachable arc is a config error worth failing early.
  JointTrajectory trajectory;
  if (config.capture_trajectory) trajectory = MakeArcTrajectory(config, truth);
  // Likewise the pose sweeps' robot poses (IK and visibility).
  std::vector<PoseSweep> eye_in_hand, joint_poses;
  if (config.capture_eye_in_hand) {
    eye_in_hand =
        PlanPoseSweeps(config, truth, config.eye_in_hand,
                       StreamSeed(config.seed, kEyeInHandPlanStream), "SimConfig.eye_in_hand");
  }
  if (config.capture_joint_poses) {
    joint_poses =
        PlanPoseSweeps(config, truth, config.joint_poses,
                       StreamSeed(config.seed, kJointPosePlanStream), "SimConfig.joint_poses");
  }

  if (config.capture_planes) {
    RunPlanes(config, truth, sweep, hb_from_cell, out, report, captures_yaml, progress, threads);
  }
  if (config.capture_spheres) {
    RunSpheres(config, truth, sweep, hb_from_cell, out, report, captures_yaml, progress, threads);
  }
  std::vector<SeatCapture> seats;
  if (config.capture_seats || config.capture_trajectory) {
    seats = DrawSeats(config, truth, config.capture_seats ? config.seat_count : 1);
  }
  if (config.capture_seats) {
    RunSeats(config, truth, seats, sweep, hb_from_cell, out, report, captures_yaml, progress,
             threads);
  }
  if (config.capture_planes || config.capture_spheres || config.capture_seats) {
    out.Write("records/linear_sweep.yaml",
              triangulation::LinearSweepRecordYaml(LinearSweepRecordOf(sweep, config)));
  }
  if (config.capture_planes) {
    // What the height fixture provides for `calibrate laser --planes`: the plate heights and the
    // plate normal in the sensor frame (the plate is level; the sensor's orientation on the
    // linear axis is known from its mounting). The distance to the plate is NOT recorded: the
    // calibration estimates it (>= 3 heights).
    const Eigen::Vector3d up_in_sensor =
        sweep.cell_from_sensor_start.linear().transpose() * Eigen::Vector3d::UnitZ();
    out.Write("records/planes.yaml",
              calib::PlaneHeightsYaml({config.plane_heights_mm, up_in_sensor}));
  }
  if (config.capture_trajectory) {
    RunTrajectory(config, truth, trajectory, seats.front(), hb_from_cell, out, report,
                  captures_yaml, progress, threads);
  }
  if (config.capture_touches) RunTouches(config, truth, out);
  if (config.capture_eye_in_hand || config.capture_joint_poses) {
    triangulation::SphereSweepList records;
    if (config.capture_eye_in_hand) {
      RunPoseSweeps(config, truth, config.eye_in_hand, eye_in_hand, "eye_in_hand",
                    "eye_in_hand_%02d", kEyeInHandStream, out, report, captures_yaml, records,
                    progress, threads);
    }
    if (config.capture_joint_poses) {
      RunPoseSweeps(config, truth, config.joint_poses, joint_poses, "joint_poses",
                    "joint_pose_%03d", kJointPoseStream, out, report, captures_yaml, records,
                    progress, threads);
    }
    out.Write("records/sphere_sweeps.yaml", triangulation::SphereSweepListYaml(records));
  }
  if (config.capture_chessboard_images) {
    RunChessboardImages(config, truth, out, threads);
    ReportProgress(progress, "chessboard images", 1.0);
  }
  if (config.capture_hand_eye_images) {
    RunHandEyeImages(config, truth, out, threads);
    ReportProgress(progress, "hand-eye images", 1.0);
  }
  if (config.capture_laser_line_images) {
    RunLaserLineImages(config, truth, sweep, out);
    ReportProgress(progress, "laser-line images", 1.0);
  }
  out.Write("truth/captures.yaml", captures_yaml);
  WriteCommonTruth(
      config, truth,
      config.capture_seats || config.capture_trajectory ? seats : std::vector<SeatCapture>{}, out);
  report.files = out.files();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

SimulationReport SimulateSeats(const SimConfig& config_in, int placements,
                               const std::string& out_dir, const ProgressCallback& progress,
                               int threads) {
  if (placements < 1 || placements > 100000) {
    throw OptionError("placements must be in [1, 100000] (got " + std::to_string(placements) + ")");
  }
  SimConfig config = config_in;
  config.seat_count = placements;
  config.capture_seats = true;
  config.capture_planes = config.capture_spheres = config.capture_trajectory = false;
  config.capture_chessboard_images = config.capture_laser_line_images = false;
  config.capture_touches = config.capture_eye_in_hand = config.capture_joint_poses = false;
  config.capture_hand_eye_images = false;
  return SimulateCell(config, out_dir, progress, threads);
}

}  // namespace lasercell::datasets
