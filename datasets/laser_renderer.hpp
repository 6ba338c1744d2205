#pragma once
// Laser-profile rendering: what the sensor's on-chip peak detector reports for one exposure.
//
// Per exposure (RenderExact): rays are cast from the emitter across the fan; consecutive hits on
// the same object (no depth jump) bracket the image columns their projections span; for each
// integer column c the fan angle whose lit point projects exactly onto column c is found by
// Illinois regula falsi on u(alpha) - c, re-intersecting the ray in double precision with the
// bracket's surface (Scene::IntersectFace, or the whole scene across patch edges). The point is
// kept when the camera sees it (front side, not grazing, occlusion ray to the projection centre
// clear), and it is bright enough: intensity = gain * albedo * cos(incidence) *
// reference_range / laser_range, saturating at 1. One peak per column (the brightest) as the
// on-chip detector reports. So a noise-free row is exact to ~1e-9 px and its 3D point lies on
// the scene surface to ~1e-10 mm (scene.hpp).
//
// Noise (ApplyNoise): row + N(0, row_sigma_px); intensity * (1 + N(0, intensity_sigma)); peaks
// below min_intensity after noise are lost; random dropouts with dropout_probability. Laser
// speckle (off by default): the row also moves by speckle_sigma_px * s_row[c] and the intensity
// is multiplied by (1 + speckle_intensity_sigma * s_int[c]), where s_row, s_int are unit-variance
// sequences correlated along the line over the speckle grain (SpeckleSequence: white noise
// filtered with a Gaussian kernel of sigma speckle_correlation_px, normalized so that sum k^2 =
// 1), drawn from a stream of their own so the white noise above is unchanged. Width is
// a plausibility model: sqrt(min_width^2 + (f * sheet_thickness * cos(view) /
// (cos(incidence) * depth))^2) px.
//
// Reflections (optional, off by default: reflection_probability = 0): a fan ray that meets a
// glossy surface (the objects named in reflective_objects, e.g. floor and pallet) also bounces
// specularly (mirror direction about the exact surface normal); where the bounced ray meets
// another surface the camera sees, that point lights a second, weaker peak of intensity
// reflection_intensity * (that surface's own diffuse intensity at that range). It is computed
// at the fan samples (not solved per column): ExposureTruth.reflection_* holds, per column, the
// brightest such ghost whose projection falls in that column (row at the sample's exact
// projection; its column is within 0.5 px). ApplyNoise keeps each ghost with
// reflection_probability (own random stream, so the primary peaks' noise is unchanged) and the
// on-chip detector reports the brighter of the two peaks: a ghost replaces a dimmer true peak
// or fills a column without one. A ghost off the laser plane triangulates to a wrong point (an
// outlier); with the laser plane vertical over a horizontal deck the mirrored fan stays in the
// plane, so the ghost is a real surface point the direct laser does not light.
//
// Units mm, rad, px; poses scene_from_sensor (the sensor frame is the camera frame).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "datasets/rng.hpp"
#include "datasets/scene.hpp"
#include "datasets/sensor.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::datasets {

/// Photometry, sampling and noise of the rendered peaks.
struct LaserRenderOptions {
  int fan_rays = 1024;                ///< Rays cast across the fan per exposure (>= 16).
  double max_range_mm = 2000.0;       ///< Laser rays end here (no peak beyond), mm.
  double intensity_gain = 8.0;        ///< Intensity of albedo 1, normal incidence, reference range.
  double reference_range_mm = 700.0;  ///< Laser range where the gain applies, mm.
  double min_intensity = 0.03;        ///< Peaks dimmer than this are lost (dark, grazing).
  double max_view_angle_deg = 85.0;   ///< Camera-side grazing cutoff, deg from the normal.
  double sheet_thickness_mm = 0.5;    ///< Laser sheet thickness, for the peak width.
  double min_width_px = 2.0;          ///< Peak width on a perfect surface, px.
  double row_sigma_px = 0.05;         ///< Gaussian noise of the peak row, px (>= 0).
  double intensity_sigma = 0.05;      ///< Relative white intensity noise per column, >= 0.
  double dropout_probability = 0.0;   ///< Probability that a valid peak is lost, [0, 1).
  /// Laser speckle: std of the correlated peak-row shift, px (>= 0). Default 0 (off) because
  /// the calibration tests' tolerances are derived from row_sigma_px alone; speckle is the
  /// fundamental limit of laser triangulation on rough surfaces (Dorsch, Haeusler, Herrmann,
  /// Appl. Opt. 1994) and a sensor of the seed's class on matt metal or plastic shows ~0.05-0.1
  /// px: set it there to simulate such a surface.
  double speckle_sigma_px = 0.0;
  /// Speckle grain along the line: sigma of the Gaussian correlation kernel, columns ([0, 100];
  /// 0 = independent columns). The grain on the sensor is ~ lambda * F# (under a pixel) but
  /// the detector's peak averages over the ~2-4 px wide stripe, so the row shift stays
  /// correlated over a few columns; 3 is typical.
  double speckle_correlation_px = 3.0;
  /// Relative std of the multiplicative intensity speckle, same grain (>= 0; 0 = off).
  double speckle_intensity_sigma = 0.0;
  double occlusion_epsilon_mm = 0.05;  ///< Occlusion rays start/stop this far from the ends.
  /// Probability that a specular ghost peak is present (per ghost column), [0, 1]; 0 = off.
  double reflection_probability = 0.0;
  /// Ghost intensity relative to the lit surface's diffuse intensity, (0, 1].
  double reflection_intensity = 0.3;
  /// Objects with a glossy surface that mirror part of the laser (scene object names).
  std::vector<std::string> reflective_objects = {"floor", "pallet"};

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "render") const;
};

/// Noise-free result of one exposure, one entry per image column.
struct ExposureTruth {
  std::vector<double> row_px;                    ///< Exact peak row; NaN when none.
  std::vector<double> intensity;                 ///< Noise-free intensity, 0..1 (0 when none).
  std::vector<double> width_px;                  ///< Peak width, px (0 when none).
  std::vector<Eigen::Vector3d> point_in_sensor;  ///< Lit point, mm (zero when none).
  std::vector<std::int32_t> object;              ///< Scene object index, -1 when none.
  // Specular ghost peaks (empty unless options.reflection_probability > 0): per column the
  // brightest ghost, NaN / 0 / zero / -1 when none.
  std::vector<double> reflection_row_px;                    ///< Ghost row.
  std::vector<double> reflection_intensity;                 ///< Ghost intensity, 0..1.
  std::vector<Eigen::Vector3d> reflection_point_in_sensor;  ///< Where the bounce lands, mm.
  std::vector<std::int32_t> reflection_object;              ///< Object the bounce lands on.

  /// Number of columns with a peak.
  std::size_t ValidCount() const;
  /// Number of columns with a ghost peak.
  std::size_t ReflectionCount() const;
};

/// Renders exposures of one sensor in one scene. Thread-safe (const methods).
class LaserRenderer {
 public:
  /// The scene must be committed and outlive the renderer. Check()s the options.
  LaserRenderer(const Scene& scene, const SensorModel& sensor, const LaserRenderOptions& options);

  /// Noise-free peaks with the sensor at `scene_from_sensor`.
  ExposureTruth RenderExact(const Eigen::Isometry3d& scene_from_sensor) const;
  /// The noisy profile a sensor would report (rows as float, NaN for none), from a seed.
  triangulation::Profile ApplyNoise(const ExposureTruth& truth, std::uint64_t seed) const;

  const SensorModel& sensor() const { return sensor_; }
  const LaserRenderOptions& options() const { return options_; }
  const Scene& scene() const { return scene_; }

  /// One fan sample of an exposure: the ray's hit and its projection (internal).
  struct FanSampleRef {
    bool valid = false;                               ///< Hit and projected.
    double alpha = 0;                                 ///< Fan angle, rad.
    RayHit hit;                                       ///< First hit.
    Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  ///< Projection, px.
  };

 private:
  // Specular ghosts of the fan samples on reflective objects (see the file comment).
  void AddReflections(const std::vector<FanSampleRef>& fan, const Eigen::Vector3d& emitter,
                      const Eigen::Vector3d& camera_center,
                      const Eigen::Isometry3d& sensor_from_scene, ExposureTruth& out) const;

  const Scene& scene_;
  SensorModel sensor_;
  LaserRenderOptions options_;
  std::vector<bool> reflective_;  // per scene object
};

/// Unit-variance laser-speckle sequence of length n, correlated over `correlation_px` columns:
/// white N(0, 1) noise filtered with the Gaussian kernel k_j ~ exp(-j^2 / (2 c^2)), |j| <=
/// ceil(4 c), normalized to sum k_j^2 = 1 so each value is N(0, 1) and the lag-d
/// autocorrelation is ~ exp(-d^2 / (4 c^2)); c = 0 gives white noise. Deterministic in `rng`.
std::vector<double> SpeckleSequence(Rng& rng, std::size_t n, double correlation_px);

/// Exposure timing of a sweep.
struct SweepTiming {
  int profiles = 350;            ///< Number of exposures (seed: 350 in 3.5 s).
  double rate_hz = 100.0;        ///< Nominal profile rate.
  double jitter_s = 20e-6;       ///< Sigma of the true exposure time about the nominal grid, s.
  double timestamp_noise_s = 0;  ///< Sigma of the recorded timestamp about the true time, s.
  /// Sigma of each recorded joint value about the true one (encoder noise), rad. The sensor
  /// pose always comes from the true joints; only the profile's recorded joints get the noise.
  double joint_noise_rad = 0;
  std::int64_t start_ns = 1'000'000'000;  ///< Timestamp of the nominal first exposure, ns.

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "timing") const;
};

/// Where the sensor is at a time (seconds since the nominal first exposure).
struct SensorState {
  Eigen::Isometry3d scene_from_sensor = Eigen::Isometry3d::Identity();
  std::vector<double> joints_rad;  ///< Recorded robot joints (empty for linear sweeps).
};

/// A rendered sweep with its ground truth.
struct SweepResult {
  triangulation::ProfileSet profiles;                ///< What the sensor reports.
  std::vector<double> exposure_time_s;               ///< True exposure times since start, s.
  std::vector<Eigen::Isometry3d> scene_from_sensor;  ///< True sensor pose per profile.
  std::size_t valid_peaks = 0;                       ///< Peaks over all profiles.
};

/// Renders a sweep: profile i is exposed at t_i = i / rate + N(0, jitter) (true), stamped
/// start_ns + round(1e9 * (t_i + N(0, timestamp_noise))), posed by `state_at(t_i)`. Profiles are
/// rendered in parallel (TBB, `threads` <= 0: all cores); every profile draws from its own
/// random stream StreamSeed(seed, i), so results do not depend on the thread count.
SweepResult RenderSweep(const LaserRenderer& renderer,
                        const std::function<SensorState(double t_s)>& state_at,
                        const SweepTiming& timing, std::uint64_t seed,
                        std::uint32_t joint_count = 0, const std::string& robot = "",
                        int threads = 0, const ProgressCallback& progress = {});

}  // namespace lasercell::datasets
