#include "datasets/laser_renderer.hpp"

#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "datasets/rng.hpp"

namespace lasercell::datasets {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDegToRad = std::numbers::pi / 180.0;

using FanSample = LaserRenderer::FanSampleRef;

// The fan angle whose hit projects onto column c, between the samples a and b: Illinois regula
// falsi on f(alpha) = u(alpha) - c (Dowell & Jarratt 1971), bracketed by the two samples.
// `trace(alpha, t_hint)` intersects the ray with the bracket's surface, `project(p)` maps a scene
// point to a pixel. False when a ray misses the surface or its hit does not project before
// |f| < 1e-9 px.
template <typename Trace, typename Project>
bool SolveColumn(const FanSample& a, const FanSample& b, int c, const Trace& trace,
                 const Project& project, std::optional<RayHit>* hit_out,
                 Eigen::Vector2d* pixel_out) {
  std::optional<RayHit>& hit = *hit_out;
  Eigen::Vector2d& pixel = *pixel_out;
  double xa = a.alpha, xb = b.alpha;
  double fa = a.pixel.x() - c, fb = b.pixel.x() - c;
  if (fa == 0) {
    hit = a.hit;
    pixel = a.pixel;
    return true;
  }
  if (fb == 0) {
    hit = b.hit;
    pixel = b.pixel;
    return true;
  }
  int side = 0;
  for (int iter = 0; iter < 40; ++iter) {
    const double x = xb - fb * (xb - xa) / (fb - fa);
    const double w = (x - a.alpha) / (b.alpha - a.alpha);
    hit = trace(x, (1 - w) * a.hit.t_mm + w * b.hit.t_mm);
    if (!hit) return false;
    const auto q = project(hit->point);
    if (!q) return false;
    pixel = *q;
    const double f = pixel.x() - c;
    if (std::abs(f) < 1e-9 || std::abs(xb - xa) < 1e-15) return true;
    if ((f > 0) == (fb > 0)) {
      xb = x;
      fb = f;
      if (side == -1) fa /= 2;
      side = -1;
    } else {
      xa = x;
      fa = f;
      if (side == 1) fb /= 2;
      side = 1;
    }
  }
  return false;
}

}  // namespace

void LaserRenderOptions::Check(const std::string& what) const {
  const auto fail = [&](const std::string& field, const std::string& rule, double got) {
    throw OptionError(what + "." + field + " " + rule + " (got " + std::to_string(got) + ")");
  };
  if (fan_rays < 16 || fan_rays > 1'000'000) fail("fan_rays", "must be in [16, 1e6]", fan_rays);
  if (!(max_range_mm > 0)) fail("max_range_mm", "must be positive", max_range_mm);
  if (!(intensity_gain > 0)) fail("intensity_gain", "must be positive", intensity_gain);
  if (!(reference_range_mm > 0)) fail("reference_range_mm", "must be positive", reference_range_mm);
  if (!(min_intensity >= 0 && min_intensity < 1))
    fail("min_intensity", "must be in [0, 1)", min_intensity);
  if (!(max_view_angle_deg > 0 && max_view_angle_deg <= 90)) {
    fail("max_view_angle_deg", "must be in (0, 90]", max_view_angle_deg);
  }
  if (!(sheet_thickness_mm >= 0)) fail("sheet_thickness_mm", "must be >= 0", sheet_thickness_mm);
  if (!(min_width_px > 0)) fail("min_width_px", "must be positive", min_width_px);
  if (!(row_sigma_px >= 0) || !std::isfinite(row_sigma_px))
    fail("row_sigma_px", "must be >= 0", row_sigma_px);
  if (!(intensity_sigma >= 0) || !std::isfinite(intensity_sigma)) {
    fail("intensity_sigma", "must be >= 0", intensity_sigma);
  }
  if (!(dropout_probability >= 0 && dropout_probability < 1)) {
    fail("dropout_probability", "must be in [0, 1)", dropout_probability);
  }
  if (!(speckle_sigma_px >= 0) || !std::isfinite(speckle_sigma_px)) {
    fail("speckle_sigma_px", "must be >= 0", speckle_sigma_px);
  }
  if (!(speckle_correlation_px >= 0 && speckle_correlation_px <= 100)) {
    fail("speckle_correlation_px", "must be in [0, 100]", speckle_correlation_px);
  }
  if (!(speckle_intensity_sigma >= 0) || !std::isfinite(speckle_intensity_sigma)) {
    fail("speckle_intensity_sigma", "must be >= 0", speckle_intensity_sigma);
  }
  if (!(occlusion_epsilon_mm > 0))
    fail("occlusion_epsilon_mm", "must be positive", occlusion_epsilon_mm);
  if (!(reflection_probability >= 0 && reflection_probability <= 1)) {
    fail("reflection_probability", "must be in [0, 1]", reflection_probability);
  }
  if (!(reflection_intensity > 0 && reflection_intensity <= 1)) {
    fail("reflection_intensity", "must be in (0, 1]", reflection_intensity);
  }
}

void SweepTiming::Check(const std::string& what) const {
  if (profiles <= 0 || profiles > 10'000'000) {
    throw OptionError(what + ".profiles must be in [1, 1e7] (got " + std::to_string(profiles) +
                      ")");
  }
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) {
    throw OptionError(what + ".rate_hz must be positive (got " + std::to_string(rate_hz) + ")");
  }
  if (!(jitter_s >= 0) || !(timestamp_noise_s >= 0) || jitter_s * rate_hz > 0.2) {
    throw OptionError(what +
                      ".jitter_s and timestamp_noise_s must be >= 0, jitter below 0.2 "
                      "profile periods (got " +
                      std::to_string(jitter_s) + ")");
  }
  if (!(joint_noise_rad >= 0) || joint_noise_rad > 0.01) {
    throw OptionError(what + ".joint_noise_rad must be in [0, 0.01] rad (got " +
                      std::to_string(joint_noise_rad) + ")");
  }
}

std::size_t ExposureTruth::ValidCount() const {
  std::size_t n = 0;
  for (double r : row_px) n += std::isnan(r) ? 0 : 1;
  return n;
}

std::size_t ExposureTruth::ReflectionCount() const {
  std::size_t n = 0;
  for (double r : reflection_row_px) n += std::isnan(r) ? 0 : 1;
  return n;
}

LaserRenderer::LaserRenderer(const Scene& scene, const SensorModel& sensor,
                             const LaserRenderOptions& options)
    : scene_(scene), sensor_(sensor), options_(options) {
  options_.Check();
  reflective_.assign(scene_.objects().size(), false);
  for (const std::string& name : options_.reflective_objects) {
    const std::int32_t k = scene_.Find(name);
    if (k >= 0) reflective_[k] = true;
  }
}

ExposureTruth LaserRenderer::RenderExact(const Eigen::Isometry3d& scene_from_sensor) const {
  const calib::CameraModel& camera = sensor_.camera;
  const LaserPlane& laser = sensor_.laser;
  const int width = camera.width_px();
  const Eigen::Isometry3d sensor_from_scene = scene_from_sensor.inverse();
  const Eigen::Matrix3d& rot = scene_from_sensor.linear();
  const Eigen::Vector3d emitter = scene_from_sensor * laser.origin_in_sensor;
  const Eigen::Vector3d camera_center = scene_from_sensor.translation();
  const int n = options_.fan_rays;
  const double half = laser.fan_angle_rad / 2;
  const double step = laser.fan_angle_rad / (n - 1);
  const double cos_view_min = std::cos(options_.max_view_angle_deg * kDegToRad);

  ExposureTruth out;
  out.row_px.assign(width, kNaN);
  out.intensity.assign(width, 0.0);
  out.width_px.assign(width, 0.0);
  out.point_in_sensor.assign(width, Eigen::Vector3d::Zero());
  out.object.assign(width, -1);

  const auto direction = [&](double alpha) -> Eigen::Vector3d {
    return rot * laser.RayDirection(alpha);
  };
  const auto project = [&](const Eigen::Vector3d& p_in_scene) {
    return ProjectInView(camera, sensor_from_scene * p_in_scene);
  };

  // 1. Cast the fan.
  std::vector<FanSample> fan(n);
  for (int i = 0; i < n; ++i) {
    FanSample& s = fan[i];
    s.alpha = -half + step * i;
    const auto hit = scene_.Intersect(emitter, direction(s.alpha), 0.0, options_.max_range_mm);
    if (!hit) continue;
    const auto q = project(hit->point);
    if (!q) continue;
    s.hit = *hit;
    s.pixel = *q;
    s.valid = true;
  }

  // 2. Per bracket of consecutive hits on one surface, solve u(alpha) = c for each column.
  for (int i = 0; i + 1 < n; ++i) {
    const FanSample& a = fan[i];
    const FanSample& b = fan[i + 1];
    if (!a.valid || !b.valid || a.hit.object != b.hit.object) continue;
    const double max_gap = 20.0 * std::max(a.hit.t_mm, b.hit.t_mm) * step + 0.5;
    if ((a.hit.point - b.hit.point).norm() > max_gap) continue;  // depth jump
    const double lo = std::min(a.pixel.x(), b.pixel.x());
    const double hi = std::max(a.pixel.x(), b.pixel.x());
    const int c0 = std::max(0, static_cast<int>(std::ceil(lo)));
    const int c1 = std::min(width - 1, static_cast<int>(std::floor(hi)));
    if (c0 > c1) continue;
    const MeshPart& geom = scene_.objects()[a.hit.object].geometry;
    const bool same_patch = geom.face_patch[a.hit.face] == geom.face_patch[b.hit.face];
    const bool analytic = same_patch && geom.patches[geom.face_patch[a.hit.face]].kind !=
                                            AnalyticSurface::Kind::kNone;

    // Intersection of the fan ray at alpha with the bracket's surface.
    const auto trace = [&](double alpha, double t_hint) -> std::optional<RayHit> {
      const Eigen::Vector3d d = direction(alpha);
      if (analytic) return scene_.IntersectFace(a.hit.object, a.hit.face, emitter, d, t_hint, 1e30);
      if (same_patch) {
        if (auto h = scene_.IntersectFace(a.hit.object, a.hit.face, emitter, d, t_hint, 1e-9))
          return h;
        if (auto h = scene_.IntersectFace(b.hit.object, b.hit.face, emitter, d, t_hint, 1e-9))
          return h;
      }
      auto h = scene_.Intersect(emitter, d, 0.0, options_.max_range_mm);
      if (h && h->object != a.hit.object) return std::nullopt;
      return h;
    };

    for (int c = c0; c <= c1; ++c) {
      std::optional<RayHit> hit;
      Eigen::Vector2d pixel;
      if (!SolveColumn(a, b, c, trace, project, &hit, &pixel)) continue;
      pixel.x() = c;  // exact by construction (to 1e-9 px)
      if (!camera.InImage(pixel)) continue;

      // 3. Visibility and photometry.
      const Eigen::Vector3d& p = hit->point;
      const Eigen::Vector3d d = (p - emitter).normalized();
      Eigen::Vector3d normal = hit->normal;
      if (normal.dot(d) > 0) normal = -normal;  // the side the laser lights
      const double cos_incidence = -normal.dot(d);
      const Eigen::Vector3d to_camera = camera_center - p;
      const double camera_distance = to_camera.norm();
      const Eigen::Vector3d view = to_camera / camera_distance;
      const double cos_view = normal.dot(view);
      if (cos_view <= cos_view_min) continue;  // back side or grazing view
      const double laser_range = (p - emitter).norm();
      double intensity = options_.intensity_gain * scene_.AlbedoAt(hit->object, p) * cos_incidence *
                         options_.reference_range_mm / laser_range;
      intensity = std::min(intensity, 1.0);
      if (intensity < options_.min_intensity) continue;
      if (intensity <= out.intensity[c]) continue;  // a brighter peak already owns the column
      if (scene_.Occluded(p, view, options_.occlusion_epsilon_mm,
                          camera_distance - options_.occlusion_epsilon_mm)) {
        continue;
      }
      const Eigen::Vector3d p_in_sensor = sensor_from_scene * p;
      const double spread = camera.intrinsics()[1] * options_.sheet_thickness_mm * cos_view /
                            (std::max(cos_incidence, 0.05) * p_in_sensor.z());
      out.row_px[c] = pixel.y();
      out.intensity[c] = intensity;
      out.width_px[c] = std::hypot(options_.min_width_px, spread);
      out.point_in_sensor[c] = p_in_sensor;
      out.object[c] = hit->object;
    }
  }
  if (options_.reflection_probability > 0)
    AddReflections(fan, emitter, camera_center, sensor_from_scene, out);
  return out;
}

void LaserRenderer::AddReflections(const std::vector<FanSampleRef>& fan,
                                   const Eigen::Vector3d& emitter,
                                   const Eigen::Vector3d& camera_center,
                                   const Eigen::Isometry3d& sensor_from_scene,
                                   ExposureTruth& out) const {
  const calib::CameraModel& camera = sensor_.camera;
  const int width = camera.width_px();
  const double cos_view_min = std::cos(options_.max_view_angle_deg * kDegToRad);
  out.reflection_row_px.assign(width, kNaN);
  out.reflection_intensity.assign(width, 0.0);
  out.reflection_point_in_sensor.assign(width, Eigen::Vector3d::Zero());
  out.reflection_object.assign(width, -1);
  for (const FanSampleRef& s : fan) {
    if (!s.valid || !reflective_[s.hit.object]) continue;
    const Eigen::Vector3d d = (s.hit.point - emitter).normalized();
    Eigen::Vector3d n = s.hit.normal;
    if (n.dot(d) > 0) n = -n;
    const Eigen::Vector3d r = d - 2.0 * d.dot(n) * n;  // mirror direction
    const auto q =
        scene_.Intersect(s.hit.point, r, options_.occlusion_epsilon_mm, options_.max_range_mm);
    if (!q || q->object == s.hit.object) continue;
    Eigen::Vector3d qn = q->normal;
    if (qn.dot(r) > 0) qn = -qn;
    const Eigen::Vector3d to_camera = camera_center - q->point;
    const double camera_distance = to_camera.norm();
    const Eigen::Vector3d view = to_camera / camera_distance;
    if (qn.dot(view) <= cos_view_min) continue;
    const auto pixel = ProjectInView(camera, sensor_from_scene * q->point);
    if (!pixel || !camera.InImage(*pixel)) continue;
    const int c = static_cast<int>(std::lround(pixel->x()));
    if (c < 0 || c >= width) continue;
    const double range = (s.hit.point - emitter).norm() + q->t_mm;
    const double intensity = std::min(1.0, options_.reflection_intensity * options_.intensity_gain *
                                               scene_.AlbedoAt(q->object, q->point) * (-qn.dot(r)) *
                                               options_.reference_range_mm / range);
    if (intensity < options_.min_intensity || intensity <= out.reflection_intensity[c]) continue;
    if (scene_.Occluded(q->point, view, options_.occlusion_epsilon_mm,
                        camera_distance - options_.occlusion_epsilon_mm)) {
      continue;
    }
    out.reflection_row_px[c] = pixel->y();
    out.reflection_intensity[c] = intensity;
    out.reflection_point_in_sensor[c] = sensor_from_scene * q->point;
    out.reflection_object[c] = q->object;
  }
}

std::vector<double> SpeckleSequence(Rng& rng, std::size_t n, double correlation_px) {
  const int half = correlation_px > 0 ? static_cast<int>(std::ceil(4.0 * correlation_px)) : 0;
  std::vector<double> kernel(2 * half + 1);
  double norm = 0;
  for (int j = -half; j <= half; ++j) {
    const double k = half == 0 ? 1.0 : std::exp(-0.5 * j * j / (correlation_px * correlation_px));
    kernel[j + half] = k;
    norm += k * k;
  }
  // sum k^2 = 1: the filtered sum of independent N(0, 1) draws is again N(0, 1).
  for (double& k : kernel) k /= std::sqrt(norm);
  std::vector<double> white(n + 2 * half);
  for (double& w : white) w = rng.Normal();
  std::vector<double> out(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    double s = 0;
    for (std::size_t j = 0; j < kernel.size(); ++j) s += kernel[j] * white[c + j];
    out[c] = s;
  }
  return out;
}

triangulation::Profile LaserRenderer::ApplyNoise(const ExposureTruth& truth,
                                                 std::uint64_t seed) const {
  const auto columns = static_cast<std::uint32_t>(truth.row_px.size());
  triangulation::Profile p = triangulation::Profile::Empty(columns);
  Rng rng(seed);
  const double rows_max = sensor_.camera.height_px() - 1;
  // Speckle is a property of the whole lit line of one exposure: drawn for every column (lit or
  // not) from its own stream, so it neither shifts nor depends on the white noise draws.
  std::vector<double> speckle_row, speckle_intensity;
  if (options_.speckle_sigma_px > 0 || options_.speckle_intensity_sigma > 0) {
    Rng speckle_rng(StreamSeed(seed, 0x5BECu));
    speckle_row = SpeckleSequence(speckle_rng, columns, options_.speckle_correlation_px);
    speckle_intensity = SpeckleSequence(speckle_rng, columns, options_.speckle_correlation_px);
  }
  for (std::uint32_t c = 0; c < columns; ++c) {
    if (std::isnan(truth.row_px[c])) continue;
    // Draw all numbers of a column first so a dropout does not shift later columns' noise.
    const double row_noise = rng.Normal();
    const double intensity_noise = rng.Normal();
    const double u = rng.Uniform();
    double intensity = truth.intensity[c] * (1.0 + options_.intensity_sigma * intensity_noise);
    double row = truth.row_px[c] + options_.row_sigma_px * row_noise;
    if (!speckle_row.empty()) {
      intensity *= std::max(0.0, 1.0 + options_.speckle_intensity_sigma * speckle_intensity[c]);
      row += options_.speckle_sigma_px * speckle_row[c];
    }
    intensity = std::min(1.0, intensity);
    if (intensity < options_.min_intensity || u < options_.dropout_probability) continue;
    if (row < 0 || row > rows_max) continue;
    p.row_px[c] = static_cast<float>(row);
    p.intensity[c] = static_cast<float>(intensity);
    p.width_px[c] = static_cast<float>(truth.width_px[c]);
  }
  if (options_.reflection_probability > 0 && !truth.reflection_row_px.empty()) {
    // Ghosts draw from a stream of their own: the true peaks' noise stays as without them.
    Rng ghost_rng(StreamSeed(seed, 0x6E05u));
    for (std::uint32_t c = 0; c < columns; ++c) {
      if (std::isnan(truth.reflection_row_px[c])) continue;
      const double u = ghost_rng.Uniform();
      const double row_noise = ghost_rng.Normal();
      const double intensity_noise = ghost_rng.Normal();
      if (u >= options_.reflection_probability) continue;
      const double intensity = std::min(
          1.0, truth.reflection_intensity[c] * (1.0 + options_.intensity_sigma * intensity_noise));
      const double row = truth.reflection_row_px[c] + options_.row_sigma_px * row_noise;
      // The detector reports the brightest peak of the column.
      if (intensity < options_.min_intensity || intensity <= p.intensity[c]) continue;
      if (row < 0 || row > rows_max) continue;
      p.row_px[c] = static_cast<float>(row);
      p.intensity[c] = static_cast<float>(intensity);
      p.width_px[c] = static_cast<float>(options_.min_width_px);
    }
  }
  return p;
}

SweepResult RenderSweep(const LaserRenderer& renderer,
                        const std::function<SensorState(double t_s)>& state_at,
                        const SweepTiming& timing, std::uint64_t seed, std::uint32_t joint_count,
                        const std::string& robot, int threads, const ProgressCallback& progress) {
  timing.Check();
  const int n = timing.profiles;
  const calib::CameraModel& camera = renderer.sensor().camera;
  SweepResult result;
  triangulation::ProfileHeader& header = result.profiles.header;
  header.image_width = static_cast<std::uint32_t>(camera.width_px());
  header.image_height = static_cast<std::uint32_t>(camera.height_px());
  header.first_column = 0;
  header.columns = header.image_width;
  header.joint_count = joint_count;
  header.robot = joint_count > 0 ? robot : "";
  result.profiles.profiles.resize(n);
  result.exposure_time_s.resize(n);
  result.scene_from_sensor.resize(n);
  std::vector<std::size_t> valid(n, 0);
  std::atomic<int> done{0};
  std::mutex progress_mutex;

  const auto render_one = [&](int i) {
    // Timing draws come from a stream of their own, so they never depend on scene content.
    Rng timing_rng(StreamSeed(seed, 2 * static_cast<std::uint64_t>(i)));
    const double t = i / timing.rate_hz + timing.jitter_s * timing_rng.Normal();
    const double stamp = t + timing.timestamp_noise_s * timing_rng.Normal();
    const SensorState state = state_at(t);
    if (state.joints_rad.size() != joint_count) {
      throw InputError("sweep: the trajectory gave " + std::to_string(state.joints_rad.size()) +
                       " joint values, expected " + std::to_string(joint_count));
    }
    const ExposureTruth truth = renderer.RenderExact(state.scene_from_sensor);
    triangulation::Profile profile =
        renderer.ApplyNoise(truth, StreamSeed(seed, 2 * static_cast<std::uint64_t>(i) + 1));
    profile.sequence = static_cast<std::uint64_t>(i);
    profile.timestamp_ns = timing.start_ns + static_cast<std::int64_t>(std::llround(stamp * 1e9));
    profile.joints_rad = state.joints_rad;
    if (timing.joint_noise_rad > 0) {
      for (double& q : profile.joints_rad) q += timing.joint_noise_rad * timing_rng.Normal();
    }
    valid[i] = profile.ValidCount();
    result.profiles.profiles[i] = std::move(profile);
    result.exposure_time_s[i] = t;
    result.scene_from_sensor[i] = state.scene_from_sensor;
    const int k = ++done;
    if (progress && (k % 16 == 0 || k == n)) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      ReportProgress(progress, "render sweep", static_cast<double>(k) / n);
    }
  };

  // Profile i writes slot i only (its own noise stream): the same sweep for any thread count.
  ParallelForChunks(threads, static_cast<std::size_t>(n), 4,
                    [&](std::size_t begin, std::size_t end) {
                      for (std::size_t i = begin; i < end; ++i) render_one(static_cast<int>(i));
                    });
  for (std::size_t v : valid) result.valid_peaks += v;
  return result;
}

}  // namespace lasercell::datasets
