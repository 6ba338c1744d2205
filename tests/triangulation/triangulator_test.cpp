#include "triangulation/triangulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include "calib/camera_model.hpp"
#include "core/error.hpp"
#include "core/ray_plane.hpp"
#include "datasets/cell.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/sensor.hpp"
#include "datasets/simulate.hpp"

namespace lasercell::triangulation {
namespace {

// The simulator's 1024 x 1024 OPENCV8 camera as a calib::CameraModel, and its true laser plane.
calib::CameraModel SimCamera(const datasets::SensorModel& sensor) { return sensor.camera; }

struct SimSensor {
  datasets::SensorModel sensor = datasets::MakeSensor(datasets::SensorOptions{});
  calib::CameraModel camera = SimCamera(sensor);
  Eigen::Vector4d plane = sensor.laser.Coefficients();
};

TEST(Triangulator, ExactPointsLieOnTheLaserPlaneAndProjectToTheirPixel) {
  SimSensor s;
  const Triangulator tri(s.camera, s.plane);
  int valid = 0;
  for (int u = 0; u < 1024; u += 37) {
    for (double v = 0.25; v < 1023; v += 41.3) {
      const Eigen::Vector3d p = tri.TriangulateExact(u, v);
      if (std::isnan(p.x())) continue;
      ++valid;
      EXPECT_NEAR(s.plane.head<3>().dot(p) + s.plane[3], 0.0, 1e-9 * p.norm());
      const Eigen::Vector2d q = s.camera.Project(p);
      EXPECT_NEAR(q.x(), u, 1e-6);
      EXPECT_NEAR(q.y(), v, 1e-6);
    }
  }
  EXPECT_GT(valid, 300);
}

// The triangulator's inline ray-plane steps are core/ray_plane.hpp's rule (min_abs_cos = sin of
// the smallest ray-plane angle), plus the depth window: same accept/reject, same point.
TEST(Triangulator, InlineRayPlaneStepsAreTheRuleOfCoreIntersectRayPlane) {
  SimSensor s;
  TriangulatorOptions options;
  options.min_ray_plane_angle_deg = 2.0;
  const Triangulator tri(s.camera, s.plane, options);
  const Eigen::Vector3d n = tri.plane().head<3>();
  const double d = tri.plane()[3];
  const double min_abs_cos = std::sin(options.min_ray_plane_angle_deg * std::numbers::pi / 180.0);
  int accepted = 0, rejected = 0;
  for (int u = 0; u < 1024; u += 53) {
    for (double v = 0.5; v < 1023; v += 29.7) {
      const Eigen::Vector3d r = s.camera.Unproject(Eigen::Vector2d(u, v));
      const Eigen::Vector3d ray(r.x() / r.z(), r.y() / r.z(), 1.0);
      const std::optional<Eigen::Vector3d> p = IntersectRayPlane(ray, n, d, min_abs_cos);
      const bool in_range = p && p->z() >= options.min_depth_mm && p->z() <= options.max_depth_mm;
      const Eigen::Vector3d exact = tri.TriangulateExact(u, v);
      const Eigen::Vector3d fast = tri.TriangulateFast(u, v);
      if (!in_range) {
        EXPECT_TRUE(std::isnan(exact.x())) << u << " " << v;
        EXPECT_TRUE(std::isnan(fast.x())) << u << " " << v;
        ++rejected;
        continue;
      }
      ++accepted;
      ASSERT_FALSE(std::isnan(exact.x())) << u << " " << v;
      EXPECT_LT((exact - *p).norm(), 1e-12 * p->norm()) << u << " " << v;
      EXPECT_LT((fast - *p).norm(), 1e-4) << u << " " << v;
    }
  }
  EXPECT_GT(accepted, 100);
  EXPECT_GT(rejected, 10);
}

// The requirement: fast and exact paths agree within 1e-4 mm over the whole image, every
// column and a dense sample of subpixel rows (offsets that vary per column so that all phases
// between knots are covered, plus the knot midpoints where Hermite error peaks).
TEST(Triangulator, FastPathAgreesWithExactPathOverTheWholeImage) {
  SimSensor s;
  const Triangulator tri(s.camera, s.plane);
  const int w = 1024, h = 1024;
  double worst = 0;
  std::size_t compared = 0, both_rejected = 0;
  std::vector<float> rows(w);
  std::vector<Eigen::Vector3d> fast(w), exact(w);
  const int kRowsPerColumn = 96;
  for (int k = 0; k < kRowsPerColumn; ++k) {
    for (int u = 0; u < w; ++u) {
      // Rows cover [-0.5, h - 0.5]: a stratified sample with a column-dependent phase.
      const double phase = std::fmod(0.618034 * (u + 1) * (k + 3), 1.0);
      const double v = -0.5 + (k + phase) * h / kRowsPerColumn;
      rows[u] = static_cast<float>(std::min(v, h - 0.5));
    }
    if (k % 8 == 0) {  // knot midpoints
      for (int u = 0; u < w; ++u) rows[u] = static_cast<float>(-0.5 + 4.0 + 8.0 * ((u + k) % 128));
    }
    const TriangulationCounts cf = tri.Triangulate(rows, 0, fast, TriangulationPath::kFast);
    const TriangulationCounts ce = tri.Triangulate(rows, 0, exact, TriangulationPath::kExact);
    EXPECT_EQ(cf.points, ce.points);
    for (int u = 0; u < w; ++u) {
      const bool fv = !std::isnan(fast[u].x()), ev = !std::isnan(exact[u].x());
      EXPECT_EQ(fv, ev) << "column " << u << " row " << rows[u];
      if (fv && ev) {
        worst = std::max(worst, (fast[u] - exact[u]).norm());
        ++compared;
      } else {
        ++both_rejected;
      }
    }
  }
  std::printf("fast vs exact: %zu points compared, %zu rejected by both, max difference %.3g mm\n",
              compared, both_rejected, worst);
  EXPECT_GT(compared, 60000u);
  EXPECT_LE(worst, 1e-4);
}

TEST(Triangulator, RaysParallelToThePlaneOrBehindTheCameraAreCountedAndNaN) {
  SimSensor s;
  // The simulator's plane: rows above the horizon meet it in front, rows below behind.
  const Triangulator tri(s.camera, s.plane);
  std::vector<float> rows(1024);
  std::vector<Eigen::Vector3d> points(1024);
  for (int u = 0; u < 1024; ++u)
    rows[u] =
        u % 4 == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(1023 - u % 300);
  for (const auto path : {TriangulationPath::kFast, TriangulationPath::kExact}) {
    const TriangulationCounts c = tri.Triangulate(rows, 0, points, path);
    EXPECT_EQ(c.no_peak, 256u);
    EXPECT_GT(c.behind_camera, 100u);  // the bottom rows look below the laser's horizon
    EXPECT_GT(c.points, 100u);
    EXPECT_EQ(
        c.points + c.no_peak + c.behind_camera + c.parallel + c.out_of_range + c.outside_image,
        1024u);
    std::size_t nan = 0;
    for (const auto& p : points) nan += std::isnan(p.x()) ? 1 : 0;
    EXPECT_EQ(nan, 1024u - c.points);
    for (int u = 0; u < 1024; ++u) {
      if (!std::isnan(points[u].x())) {
        EXPECT_GT(points[u].z(), 0.0);
      }
    }
  }
  // A plane containing the optical axis' neighbourhood rays: n = x, 100 mm to the side. Rays near
  // column cx are parallel to it; columns right of it hit it, left of it behind.
  const Triangulator side(s.camera, Eigen::Vector4d(1, 0, 0, -100));
  std::vector<float> mid(1024, 500.0f);
  const TriangulationCounts c = side.Triangulate(mid, 0, points);
  EXPECT_GT(c.parallel, 0u);
  EXPECT_GT(c.behind_camera, 400u);
  EXPECT_GT(c.points, 400u);
  // Rows outside the image.
  std::vector<float> out = {-0.6f, 1023.6f, 1e9f};
  std::vector<Eigen::Vector3d> p3(3);
  EXPECT_EQ(tri.Triangulate(out, 0, p3).outside_image, 3u);
}

TEST(Triangulator, DegeneratePlanesAreClearErrors) {
  SimSensor s;
  try {
    Triangulator(s.camera, Eigen::Vector4d(0, 1, 0, 0));
    FAIL() << "no error for a plane through the camera centre";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("passes through the camera centre"), std::string::npos)
        << e.what();
  }
  try {
    Triangulator(s.camera, Eigen::Vector4d(0, 0, 1, 500));  // z = -500: behind the camera
    FAIL() << "no error for a plane behind the camera";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("behind the camera"), std::string::npos) << e.what();
  }
  try {
    // A plane 0.5 mm from the centre: the rays (nearly) lie in it, no baseline.
    Triangulator(s.camera, Eigen::Vector4d(1, 0, 0, 0.5));
    FAIL() << "no error for a plane parallel to the rays";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("parallel"), std::string::npos) << e.what();
  }
  try {
    // Seen edge-on from far away: every hit deeper than the working range.
    Triangulator(s.camera, Eigen::Vector4d(0, 1, 0, -20000));
    FAIL() << "no error for a plane out of range";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("depths outside"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Triangulator(s.camera, Eigen::Vector4d(0, 0, 0, 1)), InputError);
  TriangulatorOptions bad;
  bad.lut_row_step_px = 0;
  try {
    Triangulator(s.camera, s.plane, bad);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("lut_row_step_px"), std::string::npos);
  }
}

TEST(Triangulator, ProfilesWiderThanTheCameraAreRejected) {
  SimSensor s;
  const Triangulator tri(s.camera, s.plane);
  std::vector<float> rows(10, 100.0f);
  std::vector<Eigen::Vector3d> p(10);
  EXPECT_THROW(tri.Triangulate(rows, 1020, p), InputError);
  std::vector<Eigen::Vector3d> short_out(9);
  EXPECT_THROW(tri.Triangulate(rows, 0, short_out), InputError);
}

// Simulator sweep of the white plane at 150 mm: each point's distance to the true plane is the
// row noise (N(0, 0.05 px)) times the sensitivity of that distance to the row, which we compute
// per point by differentiating the exact path. Normalized residuals must be N(0, 1).
// Simulation profile: ideal (SimConfig{}).
TEST(Triangulator, SimulatedPlaneSweepLiesOnTheTruePlaneWithinTheRowNoise) {
  datasets::SimConfig config;
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const calib::CameraModel camera = SimCamera(truth.sensor);
  const double height = 150.0;
  const datasets::Scene scene = datasets::MakePlaneScene(truth.layout, height, {2000, 2000});
  const datasets::LaserRenderer renderer(scene, truth.sensor, config.render);
  const datasets::LinearSweep sweep = datasets::MakeLinearSweep(config, truth.sensor);
  datasets::SweepTiming timing = config.timing;
  timing.profiles = 12;
  timing.rate_hz = 4;  // spread over the sweep
  const auto state_at = [&](double t) {
    datasets::SensorState st;
    st.scene_from_sensor = sweep.At(t);
    return st;
  };
  const datasets::SweepResult r = datasets::RenderSweep(renderer, state_at, timing, 5, 0, "", 1);
  const Triangulator tri(camera, truth.sensor.laser.Coefficients());
  const double sigma_row = config.render.row_sigma_px;
  double sum = 0, sum2 = 0, worst = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < r.profiles.profiles.size(); ++i) {
    const Profile& p = r.profiles.profiles[i];
    std::vector<Eigen::Vector3d> pts(p.row_px.size());
    tri.Triangulate(p.row_px, 0, pts);
    // White plane in the sensor frame at this exposure: m . p + e = 0.
    const Eigen::Isometry3d cell_from_sensor = r.scene_from_sensor[i];
    const Eigen::Vector3d m = cell_from_sensor.linear().transpose() * Eigen::Vector3d::UnitZ();
    const double e = cell_from_sensor.translation().z() - height;
    for (std::size_t c = 0; c < pts.size(); ++c) {
      if (std::isnan(pts[c].x())) continue;
      const double dist = m.dot(pts[c]) + e;
      const double dv = 1e-3;
      const Eigen::Vector3d dp_dv =
          (tri.TriangulateExact(c, p.row_px[c] + dv) - tri.TriangulateExact(c, p.row_px[c] - dv)) /
          (2 * dv);
      const double sigma = std::abs(m.dot(dp_dv)) * sigma_row;
      const double z = dist / sigma;
      sum += z;
      sum2 += z * z;
      worst = std::max(worst, std::abs(z));
      ++n;
    }
  }
  ASSERT_GT(n, 8000u);
  const double mean = sum / n, rms = std::sqrt(sum2 / n);
  std::printf("plane sweep: %zu points, normalized residual mean %.4f, rms %.4f, max %.2f\n", n,
              mean, rms, worst);
  EXPECT_LT(std::abs(mean), 5.0 / std::sqrt(static_cast<double>(n)));  // no bias
  EXPECT_NEAR(rms, 1.0, 5.0 / std::sqrt(2.0 * n));                     // the noise, no more
  EXPECT_LT(worst, 6.0);                                               // Gaussian tails
}

}  // namespace
}  // namespace lasercell::triangulation
