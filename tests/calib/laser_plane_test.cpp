// Laser-plane calibration (calib/laser_plane.hpp) on synthetic ground truth: the simulator's
// white-plane sweeps, a seeded column-peak generator (Monte-Carlo coverage), rendered chessboard
// images with a laser stripe; bad input; the cost functors against numeric differences.
#include "calib/laser_plane.hpp"

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/cost_functions/plane_board_joint.hpp"
#include "calib/cost_functions/plane_point_distance.hpp"
#include "core/error.hpp"
#include "core/random.hpp"
#include "datasets/camera_images.hpp"
#include "datasets/simulate.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::calib {
namespace {

constexpr double kDeg = M_PI / 180.0;

CameraModel SimCamera(const datasets::CameraIntrinsics& in) {
  const auto v = in.MrcalVector();
  return CameraModel("LENSMODEL_OPENCV8", std::vector<double>(v.begin(), v.end()), in.width_px,
                     in.height_px);
}

/// Truth plane oriented like the result (d <= 0).
void TruthPlane(const datasets::LaserPlane& laser, Eigen::Vector3d* n, double* d) {
  const Eigen::Vector4d c = laser.Coefficients();
  *n = c.head<3>();
  *d = c(3);
  if (*d > 0) {
    *n = -*n;
    *d = -*d;
  }
}

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kDeg;
}

// ---- Cost functors --------------------------------------------------------------------------

TEST(LaserPlaneCost, PlanePointDistanceMatchesNumericDifferences) {
  std::unique_ptr<ceres::CostFunction> cost(
      PlanePointDistanceCost::Create(Eigen::Vector3d(12.0, -40.0, 700.0), 3.0));
  double n[3] = {0.1, -0.9, 0.4};
  double d[1] = {-230.0};
  ceres::SphereManifold<3> sphere;
  std::vector<const ceres::Manifold*> manifolds = {&sphere, nullptr};
  ceres::NumericDiffOptions numeric;
  ceres::GradientChecker checker(cost.get(), &manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  const double* params[2] = {n, d};
  EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
}

TEST(LaserPlaneCost, HeightPlaneRayMatchesNumericDifferences) {
  const Eigen::Vector3d m = Eigen::Vector3d(0, -0.33, -0.94).normalized();
  std::unique_ptr<ceres::CostFunction> cost(HeightPlaneRayCost::Create(
      Eigen::Vector3d(0.05, 0.04, 1.0).normalized(), m, m.unitOrthogonal(), 250.0, 0.7));
  double n[3] = {0.0, -0.94, 0.34};
  double d[1] = {-235.0};
  double z[1] = {903.0};
  double a[1] = {0.01};
  ceres::SphereManifold<3> sphere;
  std::vector<const ceres::Manifold*> manifolds = {&sphere, nullptr, nullptr, nullptr};
  ceres::NumericDiffOptions numeric;
  ceres::GradientChecker checker(cost.get(), &manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  const double* params[4] = {n, d, z, a};
  EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
}

TEST(LaserPlaneCost, BoardCornerMatchesNumericDifferences) {
  std::unique_ptr<ceres::CostFunction> cost(
      BoardCornerCost::Create(Eigen::Vector3d(80, 120, 0), Eigen::Vector2d(0.05, -0.02),
                              Eigen::Vector2d(1132 / 0.1, 1130 / 0.1)));
  double pose[6] = {0.2, -0.3, 0.1, 20, -40, 700};
  ceres::NumericDiffOptions numeric;
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(cost.get(), no_manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  const double* params[1] = {pose};
  EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
}

TEST(LaserPlaneCost, StripeOnBoardMatchesNumericDifferences) {
  std::unique_ptr<ceres::CostFunction> cost(
      StripeOnBoardCost::Create(Eigen::Vector3d(0.03, 0.05, 1.0).normalized(), 40.0));
  double n[3] = {0.0, -0.94, 0.34};
  double d[1] = {-235.0};
  double pose[6] = {0.2, -0.3, 0.1, 20, -40, 700};
  ceres::SphereManifold<3> sphere;
  std::vector<const ceres::Manifold*> manifolds = {&sphere, nullptr, nullptr};
  ceres::NumericDiffOptions numeric;
  ceres::GradientChecker checker(cost.get(), &manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  const double* params[3] = {n, d, pose};
  EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
}

// ---- Method (a) on the simulator's white-plane sweeps ------------------------------------

// Simulation profile: ideal (SimConfig{} with only the white-plane sweeps captured).
datasets::SimConfig PlanesOnlyConfig() {
  datasets::SimConfig config;
  config.capture_spheres = config.capture_seats = config.capture_trajectory = false;
  config.capture_chessboard_images = config.capture_laser_line_images = false;
  config.write_meshes = config.capture_touches = false;
  config.capture_eye_in_hand = config.capture_joint_poses = false;
  return config;
}

TEST(LaserPlaneHeights, SimulatedSweepsGiveTheTruePlaneAndSensorDistance) {
  const datasets::SimConfig config = PlanesOnlyConfig();
  const test::TestDir scratch("laser_plane_sim");
  const std::string dir = scratch.path().string();
  datasets::SimulateCell(config, dir, {}, 1);
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const datasets::LinearSweep sweep = datasets::MakeLinearSweep(config, truth.sensor);
  // What the cell knows: the plate normal in the sensor frame (the sweep's orientation over the
  // levelled plate) and the heights; the sensor's distance to the plate is estimated.
  HeightPlaneOptions options;
  options.plate_normal_in_sensor =
      sweep.cell_from_sensor_start.linear().transpose() * Eigen::Vector3d::UnitZ();
  std::vector<HeightCapture> captures;
  for (std::size_t i = 0; i < config.plane_heights_mm.size(); ++i) {
    const auto set =
        triangulation::ReadProfiles(dir + "/profiles/plane_" + std::to_string(i) + ".lcp");
    HeightCapture c;
    c.name = "plane_" + std::to_string(i);
    c.height_mm = config.plane_heights_mm[i];
    for (const auto& p : set.profiles) {
      for (std::size_t j = 0; j < p.row_px.size(); ++j) {
        if (std::isfinite(p.row_px[j]))
          c.peaks_px.emplace_back(set.header.first_column + j, p.row_px[j]);
      }
    }
    captures.push_back(std::move(c));
  }
  const LaserPlaneResult r =
      CalibrateLaserPlaneFromHeights(SimCamera(config.sensor.camera), captures, options);
  Eigen::Vector3d n_true;
  double d_true = 0;
  TruthPlane(truth.sensor.laser, &n_true, &d_true);
  ASSERT_TRUE(r.converged) << r.Summary();
  EXPECT_FALSE(r.ill_conditioned);
  // Noise: row sigma 0.05 px per peak (SIMULATOR.md), ~300 peaks per column and height.
  EXPECT_LT(AngleDeg(r.normal, n_true), 0.01) << r.Summary();
  EXPECT_LT(std::abs(r.offset_mm - d_true), 0.02) << r.Summary();
  ASSERT_TRUE(r.zero_distance_mm.has_value());
  EXPECT_NEAR(*r.zero_distance_mm, sweep.cell_from_sensor_start.translation().z(),
              4 * r.zero_distance_sigma_mm + 1e-3);
  // Residuals are the mean of ~300 peaks of sigma 0.05 px: ~0.003 px.
  EXPECT_LT(r.rms_px, 0.05 / std::sqrt(100.0));
  EXPECT_EQ(r.items.size(), 3u);
  EXPECT_LT(r.normal_sigma_deg, 0.01);
}

// ---- Seeded synthetic column peaks (fast; Monte Carlo) -------------------------------------

/// Exact (column, row) pixels of the 3-D line p0 + s dir at integer columns: the line sampled
/// every 0.5 mm where it is in front of the camera within the lens's field (|x/z|, |y/z| < 0.9;
/// beyond it the rational distortion is not monotonic), each integer column solved by bisection
/// inside its bracketing segment. Columns the line crosses twice keep the first crossing.
std::map<int, double> ExactLinePixels(const CameraModel& camera, const Eigen::Vector3d& p0,
                                      const Eigen::Vector3d& dir) {
  std::map<int, double> rows;
  const double reach = 3.0 * p0.norm();
  bool have_previous = false;
  double s_prev = 0, u_prev = 0;
  for (double s = -reach; s <= reach; s += 0.5) {
    const Eigen::Vector3d p = p0 + s * dir;
    const bool in_field =
        p.z() > 1.0 && std::abs(p.x() / p.z()) < 0.9 && std::abs(p.y() / p.z()) < 0.9;
    if (!in_field) {
      have_previous = false;
      continue;
    }
    const double u = camera.Project(p).x();
    if (have_previous) {
      for (int col = static_cast<int>(std::ceil(std::min(u, u_prev)));
           col <= std::floor(std::max(u, u_prev)); ++col) {
        if (rows.count(col) > 0 || col < 0 || col >= camera.width_px()) continue;
        double lo = s_prev, hi = s;
        const double sign = u > u_prev ? 1 : -1;
        for (int it = 0; it < 60; ++it) {
          const double mid = 0.5 * (lo + hi);
          if (sign * (camera.Project(p0 + mid * dir).x() - col) > 0)
            hi = mid;
          else
            lo = mid;
        }
        rows[col] = camera.Project(p0 + 0.5 * (lo + hi) * dir).y();
      }
    }
    have_previous = true;
    s_prev = s;
    u_prev = u;
  }
  return rows;
}

struct SyntheticRig {
  CameraModel camera = SimCamera(datasets::CameraIntrinsics{});
  Eigen::Vector3d laser_n = Eigen::Vector3d(0, -0.9417419115948376, 0.33633639699815626);
  double laser_d = -235.4354778987094;
  Eigen::Vector3d m = Eigen::Vector3d(0, -0.3363363969981562, -0.9417419115948373);
  double zero_distance = 903.2193381163863;
};

/// Per image column (every `step`), the exact row where laser ∩ plate_h projects.
std::vector<Eigen::Vector2d> ExactStripe(const SyntheticRig& rig, double height, int step) {
  std::vector<Eigen::Vector2d> out;
  // The 3-D line: points on both planes; direction n x m.
  const Eigen::Vector3d dir = rig.laser_n.cross(rig.m).normalized();
  Eigen::Matrix<double, 2, 3> A;
  A.row(0) = rig.laser_n.transpose();
  A.row(1) = rig.m.transpose();
  const Eigen::Vector2d b(-rig.laser_d, height - rig.zero_distance);
  const Eigen::Vector3d p0 = A.transpose() * (A * A.transpose()).inverse() * b;
  for (const auto& [u, row] : ExactLinePixels(rig.camera, p0, dir)) {
    if (u < 20 || u >= rig.camera.width_px() - 20 || u % step != 0) continue;
    if (row < 0 || row > rig.camera.height_px() - 1) continue;
    out.emplace_back(u, row);
  }
  return out;
}

/// `peaks` noisy peaks (row sigma `sigma_px`) per exact stripe pixel.
HeightCapture NoisyCapture(const std::vector<Eigen::Vector2d>& exact, double height, int peaks,
                           double sigma_px, std::mt19937_64& rng) {
  HeightCapture c;
  c.name = std::string("h").append(std::to_string(static_cast<int>(height)));
  c.height_mm = height;
  std::normal_distribution<double> noise(0.0, sigma_px);
  for (const auto& q : exact) {
    for (int k = 0; k < peaks; ++k) c.peaks_px.emplace_back(q.x(), q.y() + noise(rng));
  }
  return c;
}

HeightCapture SyntheticCapture(const SyntheticRig& rig, double height, int peaks, double sigma_px,
                               std::mt19937_64& rng) {
  return NoisyCapture(ExactStripe(rig, height, 1), height, peaks, sigma_px, rng);
}

TEST(LaserPlaneHeights, ReportedSigmaCoversTheTruthOverMonteCarloDraws) {
  const SyntheticRig rig;
  HeightPlaneOptions options;
  options.plate_normal_in_sensor = rig.m;
  options.min_peaks_per_column = 1;
  int inside_d = 0, inside_z = 0;
  const int draws = lasercell::test::Draws(100);
  const std::vector<double> heights = {150.0, 250.0, 350.0};
  std::vector<std::vector<Eigen::Vector2d>> exact;
  for (const double h : heights) exact.push_back(ExactStripe(rig, h, 2));
  for (int draw = 0; draw < draws; ++draw) {
    std::mt19937_64 rng(1000 + draw);
    std::vector<HeightCapture> captures;
    for (std::size_t i = 0; i < heights.size(); ++i)
      captures.push_back(NoisyCapture(exact[i], heights[i], 1, 0.01, rng));
    const LaserPlaneResult r = CalibrateLaserPlaneFromHeights(rig.camera, captures, options);
    ASSERT_TRUE(r.converged);
    if (std::abs(r.offset_mm - rig.laser_d) <= r.offset_sigma_mm) ++inside_d;
    if (std::abs(*r.zero_distance_mm - rig.zero_distance) <= r.zero_distance_sigma_mm) ++inside_z;
  }
  // Gaussian 1 sigma: 68.3 %; 60-76 % over 100 draws (binomial sd 4.7 %). Noise: 0.01 px per
  // column mean, what a sweep gives (0.05 px per peak, ~300 peaks per column; the simulator's
  // sweeps give 0.003 px). At 0.03 px per column coverage drops to ~58 % and at 0.1 px to ~32 %:
  // D0 and d are then biased by ~1 sigma (the 3-height problem is nearly exactly determined and
  // its nonlinearity shows); BENCHMARKS.md says so.
  if (!lasercell::test::StatisticsAsserted()) return;
  EXPECT_GE(inside_d, 60);
  EXPECT_LE(inside_d, 76);
  EXPECT_GE(inside_z, 60);
  EXPECT_LE(inside_z, 76);
}

TEST(LaserPlaneHeights, PlateTiltTowardsTheLineIsEstimated) {
  // The true plate is tilted by 0.2 deg towards the laser line's direction; the given normal is
  // the untilted one. Estimating the tilt recovers the plane; keeping m as given does not.
  SyntheticRig rig;
  const Eigen::Vector3d m_given = rig.m;
  const Eigen::Vector3d line = rig.laser_n.cross(rig.m).normalized();
  const double tilt = 0.2 * kDeg;
  rig.m = std::cos(tilt) * m_given + std::sin(tilt) * line;
  std::mt19937_64 rng(11);
  std::vector<HeightCapture> captures;
  // 30 peaks of 0.05 px per column: ~0.01 px per column mean, as a sweep gives.
  for (const double h : {150.0, 250.0, 350.0})
    captures.push_back(SyntheticCapture(rig, h, 30, 0.05, rng));
  HeightPlaneOptions options;
  options.plate_normal_in_sensor = m_given;
  const LaserPlaneResult r = CalibrateLaserPlaneFromHeights(rig.camera, captures, options);
  std::printf("tilt %.5f +- %.5f deg; normal %.5f deg, d %.4f mm\n", r.plate_tilt_deg,
              r.plate_tilt_sigma_deg, AngleDeg(r.normal, rig.laser_n), r.offset_mm - rig.laser_d);
  EXPECT_NEAR(std::abs(r.plate_tilt_deg), 0.2, 4 * r.plate_tilt_sigma_deg + 1e-4);
  EXPECT_LT(AngleDeg(r.normal, rig.laser_n), 0.01);
  EXPECT_LT(std::abs(r.offset_mm - rig.laser_d), std::max(0.02, 3 * r.offset_sigma_mm));
  options.estimate_plate_tilt = false;
  const LaserPlaneResult fixed = CalibrateLaserPlaneFromHeights(rig.camera, captures, options);
  std::printf("tilt fixed: normal %.5f deg, d %.4f mm, rms %.4f px\n",
              AngleDeg(fixed.normal, rig.laser_n), fixed.offset_mm - rig.laser_d, fixed.rms_px);
  // Keeping the wrong m: the residuals hardly show it (the other parameters absorb most of it),
  // but the plane tilts by a third of the plate's error.
  EXPECT_GT(AngleDeg(fixed.normal, rig.laser_n), 0.03);
}

TEST(LaserPlaneHeights, TwoHeightsNeedTheSensorDistance) {
  const SyntheticRig rig;
  std::mt19937_64 rng(7);
  std::vector<HeightCapture> captures = {SyntheticCapture(rig, 150, 3, 0.05, rng),
                                         SyntheticCapture(rig, 350, 3, 0.05, rng)};
  HeightPlaneOptions options;
  options.plate_normal_in_sensor = rig.m;
  try {
    CalibrateLaserPlaneFromHeights(rig.camera, captures, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("only 2 distinct heights"), std::string::npos) << e.what();
  }
  options.zero_distance_mm = rig.zero_distance;  // known distance: 2 heights suffice
  const LaserPlaneResult r = CalibrateLaserPlaneFromHeights(rig.camera, captures, options);
  EXPECT_LT(AngleDeg(r.normal, rig.laser_n), 0.01);
  EXPECT_LT(std::abs(r.offset_mm - rig.laser_d), 0.02);
  EXPECT_TRUE(std::isnan(r.loo_max_normal_change_deg));  // 1 height left: no refit
}

// A camera model that has no ray for some stripe pixels (its distortion turns back inside the
// imager: r (1 - 3 r^2) peaks at 250 px from the centre) is an input error naming the pixel, never
// a NaN handed to the solver.
TEST(LaserPlaneHeights, ACameraWithoutRaysAtTheStripeIsRejected) {
  const SyntheticRig rig;
  std::mt19937_64 rng(7);
  std::vector<HeightCapture> captures;
  for (double h : {150.0, 250.0, 350.0}) captures.push_back(SyntheticCapture(rig, h, 3, 0.05, rng));
  std::vector<double> folded = rig.camera.intrinsics();
  std::fill(folded.begin() + 4, folded.end(), 0.0);
  folded[4] = -3.0;
  const CameraModel camera("LENSMODEL_OPENCV8", folded, rig.camera.width_px(),
                           rig.camera.height_px());
  HeightPlaneOptions options;
  options.plate_normal_in_sensor = rig.m;
  try {
    CalibrateLaserPlaneFromHeights(camera, captures, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not invertible there"), std::string::npos) << e.what();
  }
}

TEST(LaserPlaneHeights, PlanesAtOneHeightOnlyAreRejected) {
  const SyntheticRig rig;
  std::mt19937_64 rng(8);
  std::vector<HeightCapture> captures = {SyntheticCapture(rig, 250, 3, 0.05, rng),
                                         SyntheticCapture(rig, 250, 3, 0.05, rng)};
  HeightPlaneOptions options;
  options.plate_normal_in_sensor = rig.m;
  options.zero_distance_mm = rig.zero_distance;
  try {
    CalibrateLaserPlaneFromHeights(rig.camera, captures, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("planes at one height only"), std::string::npos)
        << e.what();
  }
}

TEST(LaserPlaneHeights, LaserPlaneThroughTheCameraIsIllConditioned) {
  SyntheticRig rig;
  rig.laser_d = 0;  // the laser plane contains the camera centre: rays lie in it
  rig.laser_n = Eigen::Vector3d(0, -1, 0.05).normalized();
  std::mt19937_64 rng(9);
  std::vector<HeightCapture> captures;
  for (const double h : {150.0, 250.0, 350.0})
    captures.push_back(SyntheticCapture(rig, h, 3, 0.05, rng));
  HeightPlaneOptions options;
  options.plate_normal_in_sensor = rig.m;
  try {
    CalibrateLaserPlaneFromHeights(rig.camera, captures, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("parallel to the camera rays"), std::string::npos)
        << e.what();
  }
}

TEST(LaserPlaneHeights, OptionsAreChecked) {
  HeightPlaneOptions options;
  options.inlier_band_px = 0;
  EXPECT_THROW(options.Check(), OptionError);
  options = {};
  options.plate_normal_in_sensor = Eigen::Vector3d::Zero();
  EXPECT_THROW(options.Check(), OptionError);
}

// ---- Method (b) on rendered chessboards with a laser stripe ---------------------------------

/// Renders the board and adds a Gaussian laser stripe (FWHM 3 px, amplitude 40 gray levels, below
/// saturation on the light squares) to the green channel at
/// the exact projection of laser ∩ board, per image column.
StripeImage RenderStripeImage(const datasets::ImageRenderer& renderer, const CameraModel& camera,
                              const datasets::ChessboardTarget& target,
                              const Eigen::Isometry3d& camera_from_board,
                              const Eigen::Vector3d& laser_n, double laser_d, std::uint64_t seed) {
  datasets::ImageRenderOptions options;
  const Image8 gray = renderer.RenderChessboard(target, camera_from_board, options, seed);
  StripeImage image;
  image.name = "render_" + std::to_string(seed);
  Image8& bgr = image.image;
  bgr.width = gray.width;
  bgr.height = gray.height;
  bgr.channels = 3;
  bgr.pixels.resize(static_cast<std::size_t>(gray.width) * gray.height * 3);
  for (std::size_t k = 0; k < gray.pixels.size(); ++k) {
    for (int c = 0; c < 3; ++c) bgr.pixels[3 * k + c] = gray.pixels[k];
  }
  const Eigen::Vector3d m = camera_from_board.linear().col(2);
  const double md = -m.dot(camera_from_board.translation());
  const Eigen::Vector3d dir = laser_n.cross(m).normalized();
  Eigen::Matrix<double, 2, 3> A;
  A.row(0) = laser_n.transpose();
  A.row(1) = m.transpose();
  const Eigen::Vector3d p0 =
      A.transpose() * (A * A.transpose()).inverse() * Eigen::Vector2d(-laser_d, -md);
  const double sigma = 3.0 / 2.3548;
  for (const auto& [u, row] : ExactLinePixels(camera, p0, dir)) {
    for (int v = static_cast<int>(row) - 6; v <= static_cast<int>(row) + 6; ++v) {
      if (v < 0 || v >= bgr.height) continue;
      const double g = 40.0 * std::exp(-0.5 * (v - row) * (v - row) / (sigma * sigma));
      std::uint8_t& green = bgr.pixels[(static_cast<std::size_t>(v) * bgr.width + u) * 3 + 1];
      green = static_cast<std::uint8_t>(std::min(255.0, green + g));
    }
  }
  return image;
}

struct StripeScene {
  datasets::CameraIntrinsics intrinsics;
  CameraModel camera = SimCamera(intrinsics);
  datasets::ChessboardTarget target;
  Eigen::Vector3d laser_n;
  double laser_d = 0;
  std::vector<StripeImage> images;
};

StripeScene MakeStripeScene(int count, std::uint64_t seed) {
  StripeScene scene;
  const datasets::CellTruth truth = datasets::MakeCellTruth(datasets::SimConfig{});
  TruthPlane(truth.sensor.laser, &scene.laser_n, &scene.laser_d);
  const CameraModel sim_camera = datasets::MakeCameraModel(scene.intrinsics);
  const datasets::ImageRenderer renderer(sim_camera);
  const auto poses = datasets::DrawChessboardPoses(scene.target, sim_camera, count, seed);
  for (int i = 0; i < count; ++i) {
    scene.images.push_back(RenderStripeImage(renderer, scene.camera, scene.target,
                                             poses[static_cast<std::size_t>(i)], scene.laser_n,
                                             scene.laser_d, seed + static_cast<std::uint64_t>(i)));
  }
  return scene;
}

/// One scene of 4 rendered views (seed 31), rendered once for all the stripe tests.
/// Simulation profile: ideal (ImageRenderOptions{} boards; the laser stripe is drawn here).
const StripeScene& SharedScene() {
  static const StripeScene scene = MakeStripeScene(4, 31);
  return scene;
}

TEST(LaserPlaneStripes, RenderedBoardsGiveTheTruePlane) {
  const StripeScene& scene = SharedScene();
  const LaserPlaneResult r =
      CalibrateLaserPlaneFromStripes(scene.camera, scene.images, scene.target.board);
  ASSERT_TRUE(r.converged) << r.Summary();
  std::printf(
      "detected corners: normal %.5f deg, d %.4f mm, rms %.4f mm, 1-sigma %.5f deg / %.4f mm\n",
      AngleDeg(r.normal, scene.laser_n), r.offset_mm - scene.laser_d, r.rms_mm, r.normal_sigma_deg,
      r.offset_sigma_mm);
  int used = 0;
  for (const auto& item : r.items) used += item.used ? 1 : 0;
  EXPECT_GE(used, 3);
  // Corner noise/bias of SB (0.03-0.1 px, SIMULATOR.md) tilts each board plane by ~1e-4 rad;
  // the joint refinement over the views the laser crosses, ~0.03 px stripe peaks: measured (seed
  // 31) normal 0.0020 deg, d 0.015 mm, RMS 0.013 mm. Bounds: the 0.01 deg; 0.05 mm for
  // d (one seed, 4 views).
  EXPECT_LT(AngleDeg(r.normal, scene.laser_n), 0.01) << r.Summary();
  EXPECT_LT(std::abs(r.offset_mm - scene.laser_d), 0.05) << r.Summary();
  EXPECT_LT(r.rms_mm, 0.05);
  // The reported uncertainty includes the board-pose errors (joint refinement): the true plane
  // lies within 3 sigma.
  EXPECT_LT(AngleDeg(r.normal, scene.laser_n), 3 * r.normal_sigma_deg) << r.Summary();
  EXPECT_LT(std::abs(r.offset_mm - scene.laser_d), 3 * r.offset_sigma_mm) << r.Summary();
  EXPECT_FALSE(r.ill_conditioned);
  EXPECT_FALSE(std::isnan(r.loo_max_normal_change_deg));
}

TEST(LaserPlaneStripes, WithExactCornersOnlyTheStripePeaksLimitThePlane) {
  // Same rendered views, but the board corners replaced by their true projections: what is left
  // is the stripe peaks (8-bit Gaussian stripe, three-point estimator) and the fit.
  const StripeScene& scene = SharedScene();
  const CameraModel sim_camera = datasets::MakeCameraModel(scene.intrinsics);
  const auto poses = datasets::DrawChessboardPoses(scene.target, sim_camera, 4, 31);
  const auto corners_in_target = scene.target.CornersInTarget();
  std::vector<StripeObservation> observations;
  for (std::size_t i = 0; i < scene.images.size(); ++i) {
    StripeObservation o = DetectStripe(scene.camera, scene.images[i], scene.target.board);
    // A board the laser misses has no stripe; the calibration leaves it out, and so does this.
    if (o.stripe_px.empty()) continue;
    o.corners_px.clear();
    for (const auto& c : corners_in_target)
      o.corners_px.push_back(scene.camera.Project(poses[i] * c));
    observations.push_back(o);
  }
  ASSERT_GE(observations.size(), 3u);
  const LaserPlaneResult r =
      CalibrateLaserPlaneFromStripeObservations(scene.camera, observations, scene.target.board);
  std::printf("exact corners: normal %.5f deg, d %.4f mm, rms %.4f mm\n",
              AngleDeg(r.normal, scene.laser_n), r.offset_mm - scene.laser_d, r.rms_mm);
  EXPECT_LT(AngleDeg(r.normal, scene.laser_n), 0.005) << r.Summary();
  EXPECT_LT(std::abs(r.offset_mm - scene.laser_d), 0.02) << r.Summary();
}

TEST(LaserPlaneStripes, WrongBoardLeavesTooFewUsableImages) {
  const StripeScene& scene = SharedScene();
  BoardSpec wrong = scene.target.board;
  wrong.cols += 2;
  try {
    CalibrateLaserPlaneFromStripes(scene.camera, {scene.images[0], scene.images[1]}, wrong);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("fewer than 2 usable stripe images"), std::string::npos) << what;
    // The detector names the board it does see.
    const BoardSpec right = scene.target.board;
    EXPECT_NE(what.find("but a " + std::to_string(right.cols) + "x" + std::to_string(right.rows) +
                        " one (inner corners) is visible: wrong board size"),
              std::string::npos)
        << what;
  }
}

TEST(LaserPlaneStripes, OneUsableImageIsRejected) {
  const StripeScene& scene = SharedScene();
  StripeObservation good = DetectStripe(scene.camera, scene.images[0], scene.target.board);
  ASSERT_FALSE(good.stripe_px.empty()) << good.note;
  StripeObservation no_stripe = DetectStripe(scene.camera, scene.images[1], scene.target.board);
  no_stripe.stripe_px.clear();
  try {
    CalibrateLaserPlaneFromStripeObservations(scene.camera, {good, no_stripe}, scene.target.board);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fewer than 2 usable stripe images (1 of 2)"),
              std::string::npos)
        << e.what();
  }
}

TEST(LaserPlaneStripes, UnreadableImageNamesTheFile) {
  try {
    DecodeStripeImage("this is not an image", "broken.jpg");
    FAIL() << "expected FileError";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("broken.jpg: cannot decode the image"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(DecodeStripeImage("", "empty.png"), FileError);
}

TEST(LaserPlaneStripes, ImageOfAnotherCameraSizeIsRejected) {
  StripeImage image;
  image.name = "small.png";
  image.image.width = 64;
  image.image.height = 48;
  image.image.channels = 1;
  image.image.pixels.assign(64 * 48, 0);
  const CameraModel camera = SimCamera(datasets::CameraIntrinsics{});
  try {
    DetectStripe(camera, image, BoardSpec::Chessboard(8, 6, 40.0));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("small.png' is 64x48 but the camera model is 1024x1024"),
              std::string::npos)
        << e.what();
  }
}

TEST(LaserPlaneStripes, PlaneThroughTheCameraCentreIsFlagged) {
  // Points on a plane through the camera centre (what stripe images of such a laser give).
  const CameraModel camera = SimCamera(datasets::CameraIntrinsics{});
  const Eigen::Vector3d n = Eigen::Vector3d(0, -1, 0.02).normalized();
  std::vector<StripeObservation> observations;
  const datasets::ChessboardTarget target;
  const CameraModel sim_camera = datasets::MakeCameraModel();
  const auto poses = datasets::DrawChessboardPoses(target, sim_camera, 3, 61);
  const auto corners_in_target = target.CornersInTarget();
  for (const auto& pose : poses) {
    StripeObservation o;
    o.name = "synthetic";
    for (const auto& c : corners_in_target) o.corners_px.push_back(camera.Project(pose * c));
    // Stripe: laser plane ∩ board plane, projected at many points.
    const Eigen::Vector3d m = pose.linear().col(2);
    const double md = -m.dot(pose.translation());
    const Eigen::Vector3d dir = n.cross(m).normalized();
    Eigen::Matrix<double, 2, 3> A;
    A.row(0) = n.transpose();
    A.row(1) = m.transpose();
    const Eigen::Vector3d p0 =
        A.transpose() * (A * A.transpose()).inverse() * Eigen::Vector2d(0.0, -md);
    for (int k = -100; k <= 100; ++k) {
      const Eigen::Vector3d p = p0 + 2.0 * k * dir;
      if (p.z() > 0) o.stripe_px.push_back(camera.Project(p));
    }
    observations.push_back(o);
  }
  const LaserPlaneResult r =
      CalibrateLaserPlaneFromStripeObservations(camera, observations, target.board);
  EXPECT_TRUE(r.ill_conditioned);
  ASSERT_FALSE(r.warnings.empty());
  bool found = false;
  for (const auto& w : r.warnings)
    found = found || w.find("parallel to the camera rays") != std::string::npos;
  EXPECT_TRUE(found);
}

TEST(LaserPlaneStripes, BoardSpecIsParsedAndChecked) {
  // The stripe method takes the one board spec (calib/board.hpp) and needs a chessboard.
  const BoardSpec spec = ParseBoardSpec("chessboard:6x8:40");
  EXPECT_EQ(spec.type, BoardType::kChessboard);
  EXPECT_EQ(spec.cols, 6);
  EXPECT_EQ(spec.rows, 8);
  EXPECT_EQ(spec.square_mm, 40.0);
  EXPECT_THROW(ParseBoardSpec("chessboard:6x8"), InputError);
  EXPECT_THROW(ParseBoardSpec("chessboard:1x8:40"), Error);
  const StripeScene& scene = SharedScene();
  try {
    DetectStripe(scene.camera, scene.images[0], ParseBoardSpec("charuco:6x8:40:30"));
    FAIL() << "expected OptionError";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("the stripe method needs a chessboard"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(CalibrateLaserPlaneFromStripeObservations(scene.camera, {},
                                                         ParseBoardSpec("charuco:6x8:40:30")),
               OptionError);
}

}  // namespace
}  // namespace lasercell::calib

namespace lasercell::calib {
namespace {

TEST(LaserPlaneStripes, ReportedSigmaCoversTheTruthOverMonteCarloDraws) {
  // Synthetic observations (no rendering): 6 board poses, true corner projections + N(0, 0.1 px),
  // true stripe pixels on the board + N(0, 0.05 px) in the row; the truth inside the reported
  // 1 sigma of d over 100 draws.
  const datasets::CameraIntrinsics intrinsics;
  const CameraModel camera = SimCamera(intrinsics);
  const datasets::ChessboardTarget target;
  const CameraModel sim_camera = datasets::MakeCameraModel(intrinsics);
  Eigen::Vector3d n;
  double d = 0;
  TruthPlane(datasets::MakeCellTruth(datasets::SimConfig{}).sensor.laser, &n, &d);
  const auto poses = datasets::DrawChessboardPoses(target, sim_camera, 6, 71);
  const auto corners_in_target = target.CornersInTarget();
  std::vector<std::vector<Eigen::Vector2d>> corners(poses.size()), stripes(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (const auto& c : corners_in_target) corners[i].push_back(camera.Project(poses[i] * c));
    const Eigen::Vector3d m = poses[i].linear().col(2);
    const double md = -m.dot(poses[i].translation());
    Eigen::Matrix<double, 2, 3> A;
    A.row(0) = n.transpose();
    A.row(1) = m.transpose();
    const Eigen::Vector3d p0 =
        A.transpose() * (A * A.transpose()).inverse() * Eigen::Vector2d(-d, -md);
    const Eigen::Isometry3d target_from_camera = poses[i].inverse();
    for (const auto& [u, row] : ExactLinePixels(camera, p0, n.cross(m).normalized())) {
      if (u % 3 != 0) continue;  // every third column: keeps the 100 draws fast
      // Keep the pixels whose board point lies inside the inner-corner grid.
      const Eigen::Vector3d ray = camera.Unproject(Eigen::Vector2d(u, row));
      const Eigen::Vector3d p = ray * (-md / m.dot(ray));
      const Eigen::Vector3d b = target_from_camera * p;
      const double s = target.board.square_mm;
      if (b.x() > s && b.x() < (target.SquaresX() - 1) * s && b.y() > s &&
          b.y() < (target.SquaresY() - 1) * s) {
        stripes[i].emplace_back(u, row);
      }
    }
  }
  int inside_d = 0, inside_n = 0;
  const int draws = lasercell::test::Draws(100);
  for (int draw = 0; draw < draws; ++draw) {
    std::mt19937_64 rng(500 + draw);
    std::normal_distribution<double> corner_noise(0.0, 0.1), row_noise(0.0, 0.05);
    std::vector<StripeObservation> observations;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      StripeObservation o;
      o.name = "view" + std::to_string(i);
      for (const auto& c : corners[i]) o.corners_px.push_back(c + Draws<2>(corner_noise, rng));
      for (const auto& q : stripes[i])
        o.stripe_px.push_back(q + Eigen::Vector2d(0, row_noise(rng)));
      observations.push_back(o);
    }
    const LaserPlaneResult r =
        CalibrateLaserPlaneFromStripeObservations(camera, observations, target.board);
    if (std::abs(r.offset_mm - d) <= r.offset_sigma_mm) ++inside_d;
    if (AngleDeg(r.normal, n) <= r.normal_sigma_deg) ++inside_n;
  }
  std::printf("stripe coverage: d %d %%, normal %d %%\n", inside_d, inside_n);
  if (!lasercell::test::StatisticsAsserted()) return;
  EXPECT_GE(inside_d, 60);
  EXPECT_LE(inside_d, 76);
}

}  // namespace
}  // namespace lasercell::calib
