#include "datasets/laser_renderer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <numeric>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "datasets/cell.hpp"
#include "datasets/geometry.hpp"
#include "datasets/sensor.hpp"

namespace lasercell::datasets {
namespace {

constexpr double kExactMm = 1e-6;

// Sensor above the cell looking down, laser plane normal along +x, the laser crossing the optical
// axis at `crossing` (cell frame).
Eigen::Isometry3d LookDownPose(const SensorModel& sensor, const Eigen::Vector3d& crossing,
                               double standoff_mm) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = SensorLookingDown(sensor.laser, Eigen::Vector3d::UnitX());
  pose.translation() = crossing - pose.linear() * Eigen::Vector3d(0, 0, standoff_mm);
  return pose;
}

// Simulation profile: ideal (LaserRenderOptions{}, as in SimConfig{}); a test that turns an
// effect on or off says so.
struct Fixture {
  SensorOptions sensor_options;
  SensorModel sensor = MakeSensor(sensor_options);
  CellLayout layout;
  LaserRenderOptions render;
};

TEST(Sensor, LaserGeometryMatchesTheOptions) {
  Fixture f;
  const LaserPlane& l = f.sensor.laser;
  EXPECT_NEAR(l.normal_in_sensor.norm(), 1.0, 1e-15);
  EXPECT_NEAR(l.normal_in_sensor.dot(l.center_in_sensor), 0.0, 1e-15);
  // The plane contains the emitter and the optical-axis point at the standoff.
  const Eigen::Vector4d c = l.Coefficients();
  EXPECT_NEAR(c.head<3>().dot(l.origin_in_sensor) + c[3], 0.0, 1e-12);
  EXPECT_NEAR(c.head<3>().dot(Eigen::Vector3d(0, 0, f.sensor_options.standoff_mm)) + c[3], 0.0,
              1e-12);
  // Positive fan angles move towards +x (higher columns).
  EXPECT_GT(l.Lateral().x(), 0.99);
  // The measuring range brackets the standoff along the central ray.
  const double crossing = std::hypot(f.sensor_options.baseline_mm, f.sensor_options.standoff_mm);
  EXPECT_LT(f.sensor.central_range_mm[0], crossing);
  EXPECT_GT(f.sensor.central_range_mm[1], crossing);
  // Looking down: central ray along -z, plane normal along the sweep direction.
  const Eigen::Matrix3d r = SensorLookingDown(l, Eigen::Vector3d(1, 1, 0));
  EXPECT_NEAR((r * l.center_in_sensor - Eigen::Vector3d(0, 0, -1)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((r * l.normal_in_sensor - Eigen::Vector3d(1, 1, 0).normalized()).norm(), 0, 1e-12);
}

TEST(Sensor, CameraModelTextRoundTripsThroughMrcal) {
  CameraIntrinsics c;
  c.fx_px = 1131.987654321;
  c.distortion[7] = 1.234567890123e-7;  // mrcal's own writer would print 0.000000
  const std::string text = MrcalCameraModelText(c);
  const CameraIntrinsics back = CameraIntrinsicsFromMrcalText(text, "memory");
  EXPECT_EQ(back.fx_px, c.fx_px);
  EXPECT_EQ(back.distortion, c.distortion);
  EXPECT_EQ(back.width_px, 1024);
  EXPECT_THROW(CameraIntrinsicsFromMrcalText("{ 'lensmodel': 'LENSMODEL_PINHOLE', 'intrinsics': "
                                             "[1,1,1,1], 'imagersize': [2,2]}",
                                             "pinhole.cameramodel"),
               FileError);
}

TEST(LaserRenderer, PlanePeaksAreExact) {
  Fixture f;
  const double height = 150.0;
  const Scene scene = MakePlaneScene(f.layout, height, {1500, 1500});
  const LaserRenderer renderer(scene, f.sensor, f.render);
  const Eigen::Isometry3d cell_from_sensor =
      LookDownPose(f.sensor, {12.3, -4.5, 200.0}, f.sensor_options.standoff_mm);
  const ExposureTruth truth = renderer.RenderExact(cell_from_sensor);
  ASSERT_GT(truth.ValidCount(), 900u);  // the line spans the image
  const Eigen::Vector4d laser = f.sensor.laser.Coefficients();
  for (int c = 0; c < 1024; ++c) {
    if (std::isnan(truth.row_px[c])) continue;
    const Eigen::Vector3d& p = truth.point_in_sensor[c];
    const Eigen::Vector3d p_cell = cell_from_sensor * p;
    EXPECT_NEAR(p_cell.z(), height, kExactMm) << "column " << c;
    EXPECT_NEAR(laser.head<3>().dot(p) + laser[3], 0.0, kExactMm) << "column " << c;
    const auto q = ProjectInView(f.sensor.camera, p);
    ASSERT_TRUE(q.has_value());
    EXPECT_NEAR(q->x(), c, 1e-6);
    EXPECT_NEAR(q->y(), truth.row_px[c], 1e-6);
    EXPECT_GT(truth.intensity[c], f.render.min_intensity);
    EXPECT_GE(truth.width_px[c], f.render.min_width_px);
  }
}

TEST(LaserRenderer, SpherePeaksAreExact) {
  Fixture f;
  SphereTargets spheres;
  const Scene scene = MakeSphereScene(f.layout, spheres);
  const LaserRenderer renderer(scene, f.sensor, f.render);
  const std::vector<Eigen::Vector3d> centers = spheres.CentersInCell();
  int on_sphere = 0;
  for (std::size_t s = 0; s < centers.size(); ++s) {
    // Cut each sphere off-centre so the line crosses a curved part.
    const Eigen::Vector3d crossing(centers[s].x() + 7.0, 0.0, 250.0);
    const Eigen::Isometry3d pose = LookDownPose(f.sensor, crossing, f.sensor_options.standoff_mm);
    const ExposureTruth truth = renderer.RenderExact(pose);
    const std::int32_t sphere_object = scene.Find("sphere_" + std::to_string(s));
    for (int c = 0; c < 1024; ++c) {
      if (truth.object[c] != sphere_object) continue;
      ++on_sphere;
      const Eigen::Vector3d p = pose * truth.point_in_sensor[c];
      EXPECT_NEAR((p - centers[s]).norm(), spheres.radius_mm, kExactMm) << "column " << c;
      EXPECT_GE(p.z(), centers[s].z() - 1e-9);
    }
  }
  EXPECT_GT(on_sphere, 4 * 30);
}

TEST(LaserRenderer, OccludedPointsGiveNoPeak) {
  Fixture f;
  const Eigen::Isometry3d pose = LookDownPose(f.sensor, {0, 0, 200}, f.sensor_options.standoff_mm);
  const Eigen::Vector3d camera_in_cell = pose.translation();
  // Without a wall: a full line on the plane.
  const Scene open = MakePlaneScene(f.layout, 150.0, {1500, 1500});
  const ExposureTruth free = LaserRenderer(open, f.sensor, f.render).RenderExact(pose);
  // A wall between the lit line and the camera covering the cell's +y half (the camera sits on
  // the +x side of the laser plane x = 0; the wall stands at x = 95..105, away from the laser).
  ASSERT_GT(camera_in_cell.x(), 150.0);
  Scene walled;
  Material white;
  white.albedo = 0.9;
  walled.Add({"plane",
              MakeBox(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 145)), {1500, 1500, 10}),
              white});
  walled.Add({"wall",
              MakeBox(Eigen::Isometry3d(Eigen::Translation3d(100, 400, 400)), {10, 800, 500}),
              white});
  walled.Commit();
  const ExposureTruth blocked = LaserRenderer(walled, f.sensor, f.render).RenderExact(pose);
  int hidden = 0, visible = 0;
  for (int c = 0; c < 1024; ++c) {
    if (std::isnan(free.row_px[c])) continue;
    const Eigen::Vector3d p = pose * free.point_in_sensor[c];
    // Where does the straight segment from p to the camera cross the wall's two faces?
    bool behind_wall = true, clear = true;
    for (double x : {95.0, 105.0}) {
      const double s = (x - p.x()) / (camera_in_cell.x() - p.x());
      const Eigen::Vector3d at = p + s * (camera_in_cell - p);
      behind_wall = behind_wall && at.y() > 5 && at.z() < 645 && at.z() > 155;
      clear = clear && (at.y() < -5 || at.z() > 655);
    }
    if (behind_wall) {
      EXPECT_TRUE(std::isnan(blocked.row_px[c])) << "column " << c << " should be hidden";
      ++hidden;
    } else if (clear) {
      EXPECT_FALSE(std::isnan(blocked.row_px[c])) << "column " << c << " should be seen";
      if (!std::isnan(blocked.row_px[c])) {
        EXPECT_NEAR(blocked.row_px[c], free.row_px[c], 1e-9);
      }
      ++visible;
    }
  }
  EXPECT_GT(hidden, 300);
  EXPECT_GT(visible, 300);
}

TEST(LaserRenderer, DarkSurfacesDropOut) {
  Fixture f;
  CellLayout dark = f.layout;
  dark.albedo.white_plane = 0.002;  // 8 * 0.002 = 0.016 < min_intensity
  dark.albedo.floor = 0.002;
  const Scene scene = MakePlaneScene(dark, 150.0, {1500, 1500});
  const Eigen::Isometry3d pose = LookDownPose(f.sensor, {0, 0, 200}, f.sensor_options.standoff_mm);
  EXPECT_EQ(LaserRenderer(scene, f.sensor, f.render).RenderExact(pose).ValidCount(), 0u);
  const Scene bright = MakePlaneScene(f.layout, 150.0, {1500, 1500});
  EXPECT_GT(LaserRenderer(bright, f.sensor, f.render).RenderExact(pose).ValidCount(), 900u);
}

// Simulation profile: ideal, with the row noise at 0.25 px and the intensity noise off.
TEST(LaserRenderer, RowNoiseHasTheConfiguredSigma) {
  Fixture f;
  f.render.row_sigma_px = 0.25;
  f.render.intensity_sigma = 0.0;
  const Scene scene = MakePlaneScene(f.layout, 150.0, {1500, 1500});
  const LaserRenderer renderer(scene, f.sensor, f.render);
  const Eigen::Isometry3d pose = LookDownPose(f.sensor, {0, 0, 200}, f.sensor_options.standoff_mm);
  const ExposureTruth truth = renderer.RenderExact(pose);
  std::vector<double> residuals;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const triangulation::Profile p = renderer.ApplyNoise(truth, 1000 + seed);
    for (int c = 0; c < 1024; ++c) {
      if (std::isnan(truth.row_px[c])) continue;
      ASSERT_FALSE(std::isnan(p.row_px[c]));
      residuals.push_back(static_cast<double>(p.row_px[c]) - truth.row_px[c]);
    }
  }
  const double n = static_cast<double>(residuals.size());
  ASSERT_GT(n, 18000);
  const double mean = std::accumulate(residuals.begin(), residuals.end(), 0.0) / n;
  double ss = 0;
  for (double r : residuals) ss += (r - mean) * (r - mean);
  const double sigma = std::sqrt(ss / (n - 1));
  // Standard error of the mean sigma/sqrt(n); of the sample sigma ~ sigma/sqrt(2n) (plus float
  // rounding of the rows, 3e-5 px). Bounds at 5 standard errors.
  EXPECT_NEAR(mean, 0.0, 5 * 0.25 / std::sqrt(n));
  EXPECT_NEAR(sigma, 0.25, 5 * 0.25 / std::sqrt(2 * n));
  // Different seeds give different noise; the same seed the same.
  EXPECT_NE(renderer.ApplyNoise(truth, 1).row_px, renderer.ApplyNoise(truth, 2).row_px);
  const auto a = renderer.ApplyNoise(truth, 3);
  const auto b = renderer.ApplyNoise(truth, 3);
  EXPECT_EQ(triangulation::EncodeProfiles({{}, {a}}), triangulation::EncodeProfiles({{}, {b}}));
}

// Speckle: the row shift of each exposure is N(0, speckle_sigma_px) per column and correlated
// over the grain: lag-1 autocorrelation exp(-1 / (4 c^2)) = 0.984 for c = 4 columns, 0 for c = 0.
// Simulation profile: ideal, plus speckle, with the white row and intensity noise off.
TEST(LaserRenderer, SpeckleHasTheConfiguredSigmaAndGrain) {
  Fixture f;
  f.render.row_sigma_px = 0.0;
  f.render.intensity_sigma = 0.0;
  f.render.speckle_sigma_px = 0.08;
  const Scene scene = MakePlaneScene(f.layout, 150.0, {1500, 1500});
  const Eigen::Isometry3d pose = LookDownPose(f.sensor, {0, 0, 200}, f.sensor_options.standoff_mm);
  struct Stats {
    double n = 0, mean = 0, sigma = 0, lag1 = 0;
  };
  const auto measure = [&](double grain_px) {
    f.render.speckle_correlation_px = grain_px;
    const LaserRenderer renderer(scene, f.sensor, f.render);
    const ExposureTruth truth = renderer.RenderExact(pose);
    std::vector<std::vector<double>> lines;
    Stats s;
    for (std::uint64_t seed = 0; seed < 20; ++seed) {
      const triangulation::Profile p = renderer.ApplyNoise(truth, 500 + seed);
      std::vector<double> line(1024, std::numeric_limits<double>::quiet_NaN());
      for (int c = 0; c < 1024; ++c) {
        if (std::isnan(truth.row_px[c])) continue;
        EXPECT_FALSE(std::isnan(p.row_px[c]));
        line[c] = static_cast<double>(p.row_px[c]) - truth.row_px[c];
        s.mean += line[c];
        s.n += 1;
      }
      lines.push_back(line);
    }
    s.mean /= s.n;
    double ss = 0, cross = 0, pairs = 0;
    for (const auto& line : lines) {
      for (int c = 0; c < 1024; ++c) {
        if (std::isnan(line[c])) continue;
        ss += (line[c] - s.mean) * (line[c] - s.mean);
        if (c + 1 < 1024 && !std::isnan(line[c + 1])) {
          cross += (line[c] - s.mean) * (line[c + 1] - s.mean);
          pairs += 1;
        }
      }
    }
    s.sigma = std::sqrt(ss / (s.n - 1));
    s.lag1 = (cross / pairs) / (ss / s.n);
    return s;
  };
  for (double grain : {0.0, 4.0}) {
    SCOPED_TRACE("grain " + std::to_string(grain));
    const Stats s = measure(grain);
    ASSERT_GT(s.n, 18000);
    // Correlated samples: the effective count is n / sum_d rho(d)^2 = n / (c sqrt(2 pi)) (~10
    // for c = 4); the sample sigma's standard error is sigma / sqrt(2 n_eff), 5 of them allowed
    // (plus 3e-5 px float rounding of the rows).
    const double n_eff = s.n / std::max(1.0, grain * std::sqrt(2 * std::numbers::pi));
    EXPECT_NEAR(s.sigma, 0.08, 5 * 0.08 / std::sqrt(2 * n_eff) + 3e-5);
    EXPECT_NEAR(s.mean, 0.0, 5 * 0.08 / std::sqrt(n_eff));
    if (grain == 0) {
      EXPECT_NEAR(s.lag1, 0.0, 5 / std::sqrt(s.n));
    } else {
      EXPECT_NEAR(s.lag1, std::exp(-1.0 / (4 * grain * grain)), 0.02);
    }
  }
  // Speckle draws from its own stream: the white row noise of a seed is unchanged by it.
  f.render.row_sigma_px = 0.25;
  f.render.speckle_correlation_px = 3.0;
  const LaserRenderer with(scene, f.sensor, f.render);
  const ExposureTruth truth = with.RenderExact(pose);
  f.render.speckle_sigma_px = 0.0;
  const LaserRenderer without(scene, f.sensor, f.render);
  f.render.row_sigma_px = 0.0;
  f.render.speckle_sigma_px = 0.08;
  const LaserRenderer only_speckle(scene, f.sensor, f.render);
  const auto a = with.ApplyNoise(truth, 77), b = without.ApplyNoise(truth, 77),
             c = only_speckle.ApplyNoise(truth, 77);
  int compared = 0;
  for (int col = 0; col < 1024; ++col) {
    if (std::isnan(truth.row_px[col])) continue;
    const double white = b.row_px[col] - truth.row_px[col];
    const double speckle = c.row_px[col] - truth.row_px[col];
    EXPECT_NEAR(a.row_px[col] - truth.row_px[col], white + speckle, 2e-4);
    ++compared;
  }
  EXPECT_GT(compared, 900);
  // Intensity speckle: on a dim surface (no saturation) the relative intensity varies.
  f.render.speckle_sigma_px = 0.0;
  f.render.speckle_intensity_sigma = 0.2;
  f.render.intensity_gain = 0.5;
  const LaserRenderer dim(scene, f.sensor, f.render);
  const ExposureTruth dim_truth = dim.RenderExact(pose);
  const auto d = dim.ApplyNoise(dim_truth, 5);
  double ss = 0;
  int n = 0;
  for (int col = 0; col < 1024; ++col) {
    if (std::isnan(d.row_px[col])) continue;
    EXPECT_EQ(d.row_px[col], static_cast<float>(dim_truth.row_px[col]));
    const double rel = d.intensity[col] / dim_truth.intensity[col] - 1.0;
    ss += rel * rel;
    ++n;
  }
  ASSERT_GT(n, 500);
  // One exposure of grain 3: n_eff ~ n / 7.5; 5 standard errors.
  EXPECT_NEAR(std::sqrt(ss / n), 0.2, 5 * 0.2 / std::sqrt(2.0 * n / 7.5));
}

// Simulation profile: ideal, plus encoder noise (2e-5 rad) on the recorded joints.
TEST(LaserRenderer, EncoderNoiseChangesOnlyTheRecordedJoints) {
  Fixture f;
  const ChairSeat seat = MakeChairSeat();
  const Scene scene =
      MakeSeatScene(f.layout, seat, DrawSeatPlacement({}, seat, 9, 0).cell_from_part);
  const LaserRenderer renderer(scene, f.sensor, f.render);
  SweepTiming timing;
  timing.profiles = 400;
  const Eigen::Isometry3d start =
      LookDownPose(f.sensor, {-200, 0, 250}, f.sensor_options.standoff_mm);
  const std::vector<double> q_true = {0.1, -1.2, 1.0, -0.4, 1.5, 0.3};
  const auto state_at = [&](double t) {
    SensorState s;
    s.scene_from_sensor = Eigen::Translation3d(100.0 * t, 0, 0) * start;
    s.joints_rad = q_true;
    return s;
  };
  const SweepResult exact = RenderSweep(renderer, state_at, timing, 42, 6, "vision_robot", 2);
  timing.joint_noise_rad = 2e-5;
  const SweepResult noisy = RenderSweep(renderer, state_at, timing, 42, 6, "vision_robot", 2);
  double sum_sq = 0;
  int n = 0;
  for (int i = 0; i < timing.profiles; ++i) {
    const auto& a = exact.profiles.profiles[i];
    const auto& b = noisy.profiles.profiles[i];
    EXPECT_EQ(a.joints_rad, q_true);
    // Same peaks, same timestamps: the noise is in the record only.
    EXPECT_EQ(a.timestamp_ns, b.timestamp_ns);
    ASSERT_EQ(a.row_px.size(), b.row_px.size());
    EXPECT_EQ(0, std::memcmp(a.row_px.data(), b.row_px.data(), a.row_px.size() * sizeof(float)));
    for (int j = 0; j < 6; ++j) {
      sum_sq += (b.joints_rad[j] - q_true[j]) * (b.joints_rad[j] - q_true[j]);
      ++n;
    }
  }
  // 2400 draws: the sample sigma is within 10 % of the configured one (5 sigma of its spread).
  EXPECT_NEAR(std::sqrt(sum_sq / n), 2e-5, 0.1 * 2e-5);
  timing.joint_noise_rad = -1;
  EXPECT_THROW(timing.Check(), OptionError);
}

TEST(LaserRenderer, SweepsAreIdenticalForAnyThreadCount) {
  Fixture f;
  const ChairSeat seat = MakeChairSeat();
  const Scene scene =
      MakeSeatScene(f.layout, seat, DrawSeatPlacement({}, seat, 9, 0).cell_from_part);
  const LaserRenderer renderer(scene, f.sensor, f.render);
  SweepTiming timing;
  timing.profiles = 24;
  const Eigen::Isometry3d start =
      LookDownPose(f.sensor, {-200, 0, 250}, f.sensor_options.standoff_mm);
  const auto state_at = [&](double t) {
    SensorState s;
    s.scene_from_sensor = Eigen::Translation3d(400.0 * t, 0, 0) * start;
    return s;
  };
  const SweepResult one = RenderSweep(renderer, state_at, timing, 42, 0, "", 1);
  const SweepResult two = RenderSweep(renderer, state_at, timing, 42, 0, "", 2);
  const SweepResult other = RenderSweep(renderer, state_at, timing, 43, 0, "", 2);
  EXPECT_GT(one.valid_peaks, 24u * 300u);
  EXPECT_EQ(triangulation::EncodeProfiles(one.profiles),
            triangulation::EncodeProfiles(two.profiles));
  EXPECT_NE(triangulation::EncodeProfiles(one.profiles),
            triangulation::EncodeProfiles(other.profiles));
  // Timestamps: nominal grid plus jitter, in ns.
  for (int i = 0; i < timing.profiles; ++i) {
    const double nominal_ns = timing.start_ns + 1e9 * i / timing.rate_hz;
    EXPECT_NEAR(static_cast<double>(one.profiles.profiles[i].timestamp_ns), nominal_ns,
                6 * timing.jitter_s * 1e9 + 1);
    EXPECT_EQ(one.profiles.profiles[i].sequence, static_cast<std::uint64_t>(i));
  }
}

}  // namespace
}  // namespace lasercell::datasets

namespace lasercell::datasets {
namespace {

// Simulation profile: ideal, plus specular ghosts (reflection_probability 1).
TEST(LaserRenderer, SpecularReflectionsGiveWeakerGhostPeaksOnlyWhenEnabled) {
  Fixture f;
  SphereTargets spheres;
  const Scene scene = MakeSphereScene(f.layout, spheres);
  const LaserRenderer off(scene, f.sensor, f.render);  // default: reflections off
  EXPECT_EQ(f.render.reflection_probability, 0.0);
  LaserRenderOptions with = f.render;
  with.reflection_probability = 1.0;
  with.reflection_intensity = 0.3;
  const LaserRenderer on(scene, f.sensor, with);
  const Eigen::Vector4d laser_plane = f.sensor.laser.Coefficients();
  std::size_t ghosts = 0, ghosts_reported = 0, off_plane = 0;
  double worst_projection_px = 0;
  // Sweep the line across the stands: rays hitting the deck next to a stand bounce onto it.
  for (const Eigen::Vector3d& center : spheres.CentersInCell()) {
    for (double dx = -60; dx <= 60; dx += 4) {
      const Eigen::Vector3d crossing(center.x() + dx, center.y(), 244.0);
      const Eigen::Isometry3d pose = LookDownPose(f.sensor, crossing, f.sensor_options.standoff_mm);
      const ExposureTruth a = off.RenderExact(pose);
      const ExposureTruth b = on.RenderExact(pose);
      EXPECT_TRUE(a.reflection_row_px.empty());
      // The true peaks are the same with or without ghosts.
      for (int c = 0; c < 1024; ++c) {
        EXPECT_TRUE(a.row_px[c] == b.row_px[c] ||
                    (std::isnan(a.row_px[c]) && std::isnan(b.row_px[c])));
      }
      for (int c = 0; c < 1024; ++c) {
        if (std::isnan(b.reflection_row_px[c])) continue;
        ++ghosts;
        const Eigen::Vector3d& q = b.reflection_point_in_sensor[c];
        // A ghost lies on the surface the camera sees first along its pixel's ray.
        const Eigen::Vector3d q_cell = pose * q;
        const auto seen = scene.Intersect(pose.translation(), q_cell - pose.translation());
        ASSERT_TRUE(seen.has_value());
        EXPECT_LT((seen->point - q_cell).norm(), 1e-6) << c;
        EXPECT_EQ(seen->object, b.reflection_object[c]);
        if (std::abs(laser_plane.head<3>().dot(q) + laser_plane[3]) > 0.5) ++off_plane;
        const Eigen::Vector2d px = *ProjectInView(f.sensor.camera, q);
        worst_projection_px =
            std::max({worst_projection_px, std::abs(px.y() - b.reflection_row_px[c]),
                      std::abs(px.x() - c) - 0.5});
        // Weaker than a direct hit of that surface: at most reflection_intensity * gain * albedo.
        const double albedo = scene.AlbedoAt(b.reflection_object[c], pose * q);
        EXPECT_LE(b.reflection_intensity[c],
                  with.reflection_intensity * with.intensity_gain * albedo);
      }
      // The detector reports a ghost only where it outshines the true peak.
      const triangulation::Profile p = on.ApplyNoise(b, 99);
      const triangulation::Profile p_off = off.ApplyNoise(a, 99);
      for (int c = 0; c < 1024; ++c) {
        const bool same = p.row_px[c] == p_off.row_px[c] ||
                          (std::isnan(p.row_px[c]) && std::isnan(p_off.row_px[c]));
        if (same) continue;
        ++ghosts_reported;
        ASSERT_FALSE(std::isnan(b.reflection_row_px[c])) << c;
        EXPECT_NEAR(p.row_px[c], b.reflection_row_px[c], 1.0) << c;
        EXPECT_GT(p.intensity[c], std::isnan(p_off.row_px[c]) ? 0.0f : p_off.intensity[c]);
      }
    }
  }
  EXPECT_GT(ghosts, 20u);
  EXPECT_GT(ghosts_reported, 0u);
  EXPECT_LE(worst_projection_px, 1e-6);
  std::printf(
      "reflections: %zu ghost columns (%zu off the laser plane), %zu reported as the "
      "column's peak\n",
      ghosts, off_plane, ghosts_reported);
  // Probability 0 means off, and the option is checked.
  with.reflection_probability = 1.5;
  EXPECT_THROW(LaserRenderer(scene, f.sensor, with), OptionError);
}

}  // namespace
}  // namespace lasercell::datasets
