#pragma once
// Laser triangulation: a peak at (column u, subpixel row v) -> the camera ray of that pixel ->
// its intersection with the laser plane -> a 3D point in the `sensor` frame.
//
// Conventions: the `sensor` frame is the camera frame (mrcal: +x along columns, +y along rows,
// +z the optical axis, origin at the projection centre); pixel centres at integer coordinates;
// the laser plane is n . p + d = 0 in the sensor frame (n unit, d in mm); points in mm.
//
// Two paths giving the same points:
//  - exact: every pixel unprojected by mrcal (CameraModel::UnprojectMany), ray r = (x, y, 1)
//    in normalized coordinates, p = r / w with w = -(n . r) / d (= 1 / depth);
//  - fast: per image column, the normalized ray x(v), y(v) as a piecewise cubic in the row:
//    cubic Hermite interpolation between knots every `lut_row_step_px` rows, with the values
//    from mrcal unprojection and the exact derivatives dx/dv, dy/dv from the implicit function
//    theorem on mrcal's projection Jacobian (d(x, y)/dv = (dq/d(x, y))^-1 e_v). Each interval is
//    stored as 8 polynomial coefficients (one 64-byte cache line); a point costs one lookup,
//    two Horner cubics, one division. The interpolation error is h^4 / 384 * max|4th derivative|
//    per coordinate; a point's error is that times its depth. Measured on the 1024 x 1024
//    OPENCV8 simulator camera (worst at the image corners): 1.1e-8 relative at h = 16 (1.07e-4
//    mm at 9.8 m depth: too much), 8e-10 at h = 8 (7.3e-6 mm at 9.1 m): h = 8 is the default.
// Rejected points are NaN and counted by reason, identically on both paths: row outside the
// image, ray within `min_ray_plane_angle_deg` of the plane (nearly parallel), the plane behind
// the camera along the ray, or a depth outside [min_depth_mm, max_depth_mm].

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"

namespace lasercell::triangulation {

/// How a triangulator turns pixels into rays.
enum class TriangulationPath {
  kFast,   ///< Per-column cubic lookup tables (the default).
  kExact,  ///< mrcal unprojection of every pixel.
};

/// Validity limits and lookup-table resolution.
struct TriangulatorOptions {
  /// Rays closer than this angle to the laser plane give NaN (nearly parallel), deg, [0, 90).
  double min_ray_plane_angle_deg = 1.0;
  /// Points deeper than this along the optical axis give NaN (beyond any working range), mm.
  double max_depth_mm = 10000.0;
  /// Points closer than this (depth along the optical axis) give NaN, mm; a plane passing closer
  /// than this to the camera centre is refused (no triangulation baseline). > 0, < max_depth_mm.
  double min_depth_mm = 1.0;
  /// Rows between lookup-table knots, px; (0, 64].
  double lut_row_step_px = 8.0;
  /// Construction fails (InputError) when fewer than this fraction of a grid of image rays
  /// meets the plane validly: the plane is then (nearly) parallel to the camera rays or behind
  /// the camera, i.e. not a laser plane of this camera. (0, 1].
  double min_valid_ray_fraction = 0.02;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "TriangulatorOptions") const;
};

/// Counts of triangulated and rejected peaks.
struct TriangulationCounts {
  std::size_t points = 0;         ///< Valid 3D points.
  std::size_t no_peak = 0;        ///< Columns without a peak (row NaN).
  std::size_t outside_image = 0;  ///< Rows outside [-0.5, height - 0.5] or columns outside.
  std::size_t parallel = 0;       ///< Rays (nearly) parallel to the laser plane.
  std::size_t behind_camera = 0;  ///< The plane meets the ray behind the camera.
  std::size_t out_of_range = 0;   ///< Depth outside [min_depth_mm, max_depth_mm].

  TriangulationCounts& operator+=(const TriangulationCounts& o);
  /// e.g. "1000 points; rejected: 24 no peak, 0 outside image, 0 parallel, 0 behind, 0 out of
  /// range".
  std::string Summary() const;
};

/// Turns (column, row) peaks into points in the sensor frame. Immutable after construction;
/// thread-safe.
class Triangulator {
 public:
  /// `plane_in_sensor` = (n, d) with n . p + d = 0 (n is normalized with d when not unit).
  /// Builds the lookup tables (one mrcal unprojection per knot). Throws InputError when the
  /// plane is not finite, passes (nearly) through the camera centre (|d| < min_depth_mm: the
  /// camera rays then lie in it or meet it at the centre, no triangulation baseline), or fewer
  /// than min_valid_ray_fraction of the image's rays meet it validly (the message gives the
  /// counts: parallel, behind, out of range); OptionError for bad options.
  Triangulator(calib::CameraModel camera, const Eigen::Vector4d& plane_in_sensor,
               const TriangulatorOptions& options = {});

  /// Points of one profile: column j is image column first_column + j; rows NaN = no peak.
  /// `points` receives rows.size() points (NaN where rejected). Returns the counts.
  TriangulationCounts Triangulate(std::span<const float> rows, std::uint32_t first_column,
                                  std::span<Eigen::Vector3d> points,
                                  TriangulationPath path = TriangulationPath::kFast) const;

  /// One point by the exact path (NaN when rejected).
  Eigen::Vector3d TriangulateExact(double column, double row) const;
  /// One point by the fast path; the column must be an integer column of the image.
  Eigen::Vector3d TriangulateFast(int column, double row) const;

  const calib::CameraModel& camera() const { return camera_; }
  /// (n, d), n unit.
  const Eigen::Vector4d& plane() const { return plane_; }
  const TriangulatorOptions& options() const { return options_; }
  /// Knot intervals per column.
  int IntervalsPerColumn() const { return intervals_; }

 private:
  // Reason a normalized ray (x, y, 1) is rejected, or kOk.
  enum class Reject : std::uint8_t { kOk, kParallel, kBehind, kOutOfRange };
  Reject Classify(double x, double y) const;
  static void Count(Reject r, TriangulationCounts& counts);
  void BuildTables();

  calib::CameraModel camera_;
  Eigen::Vector4d plane_;
  TriangulatorOptions options_;
  double min_w_ = 0;      // 1 / max_depth_mm
  double max_w_ = 0;      // 1 / min_depth_mm
  double sin2_min_ = 0;   // sin^2(min angle)
  double row_lo_ = -0.5;  // table domain in rows
  double inv_step_ = 0;
  int intervals_ = 0;
  // Per column, per interval: x(t) = c0 + t (c1 + t (c2 + t c3)), y(t) likewise, t in [0, 1).
  struct alignas(64) Cubic2 {
    double x[4];
    double y[4];
  };
  std::vector<Cubic2> table_;
};

}  // namespace lasercell::triangulation
