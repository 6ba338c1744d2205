#include "triangulation/triangulator.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>

#include "core/error.hpp"

namespace lasercell::triangulation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const Eigen::Vector3d kNaNPoint(kNaN, kNaN, kNaN);

std::string PlaneText(const Eigen::Vector4d& p) {
  std::ostringstream o;
  o << "n = (" << p[0] << ", " << p[1] << ", " << p[2] << "), d = " << p[3] << " mm";
  return o.str();
}

}  // namespace

void TriangulatorOptions::Check(const std::string& what) const {
  if (!(min_ray_plane_angle_deg >= 0 && min_ray_plane_angle_deg < 90)) {
    throw OptionError(what + ".min_ray_plane_angle_deg must be in [0, 90) deg, got " +
                      std::to_string(min_ray_plane_angle_deg));
  }
  if (!(max_depth_mm > 0)) {
    throw OptionError(what + ".max_depth_mm must be positive, got " + std::to_string(max_depth_mm));
  }
  if (!(min_depth_mm > 0 && min_depth_mm < max_depth_mm)) {
    throw OptionError(what + ".min_depth_mm must be positive and below max_depth_mm, got " +
                      std::to_string(min_depth_mm));
  }
  if (!(lut_row_step_px > 0 && lut_row_step_px <= 64)) {
    throw OptionError(what + ".lut_row_step_px must be in (0, 64] px, got " +
                      std::to_string(lut_row_step_px));
  }
  if (!(min_valid_ray_fraction > 0 && min_valid_ray_fraction <= 1)) {
    throw OptionError(what + ".min_valid_ray_fraction must be in (0, 1], got " +
                      std::to_string(min_valid_ray_fraction));
  }
}

TriangulationCounts& TriangulationCounts::operator+=(const TriangulationCounts& o) {
  points += o.points;
  no_peak += o.no_peak;
  outside_image += o.outside_image;
  parallel += o.parallel;
  behind_camera += o.behind_camera;
  out_of_range += o.out_of_range;
  return *this;
}

std::string TriangulationCounts::Summary() const {
  char b[256];
  std::snprintf(b, sizeof b,
                "%zu points; rejected: %zu no peak, %zu outside image, %zu parallel to the laser "
                "plane, %zu behind the camera, %zu out of depth range",
                points, no_peak, outside_image, parallel, behind_camera, out_of_range);
  return b;
}

Triangulator::Triangulator(calib::CameraModel camera, const Eigen::Vector4d& plane_in_sensor,
                           const TriangulatorOptions& options)
    : camera_(std::move(camera)), plane_(plane_in_sensor), options_(options) {
  options_.Check();
  if (!plane_.allFinite()) {
    throw InputError("laser plane " + PlaneText(plane_) + " is not finite");
  }
  const double n = plane_.head<3>().norm();
  if (!(n > 1e-12)) {
    throw InputError("laser plane " + PlaneText(plane_) + " has a zero normal");
  }
  plane_ /= n;
  if (std::abs(plane_[3]) < options_.min_depth_mm) {
    throw InputError("laser plane " + PlaneText(plane_) +
                     " passes through the camera centre (closer than min_depth_mm = " +
                     std::to_string(options_.min_depth_mm) +
                     " mm): the camera rays are parallel to it (lie in it) or meet it at the "
                     "centre, so there is no triangulation baseline; check the plane's frame (it "
                     "must be the sensor = camera frame) and units (mm)");
  }
  min_w_ = 1.0 / options_.max_depth_mm;
  max_w_ = 1.0 / options_.min_depth_mm;
  const double s = std::sin(options_.min_ray_plane_angle_deg * std::numbers::pi / 180.0);
  sin2_min_ = s * s;

  // Degeneracy check over a 48 x 48 grid of image rays.
  const int kGrid = 48;
  std::vector<Eigen::Vector2d> pixels;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      pixels.emplace_back((camera_.width_px() - 1) * (i + 0.5) / kGrid,
                          (camera_.height_px() - 1) * (j + 0.5) / kGrid);
    }
  }
  const std::vector<Eigen::Vector3d> rays = camera_.UnprojectMany(pixels);
  TriangulationCounts grid;
  for (const Eigen::Vector3d& r : rays) {
    if (!(r.z() > 1e-9)) {
      ++grid.behind_camera;
      continue;
    }
    Count(Classify(r.x() / r.z(), r.y() / r.z()), grid);
  }
  if (grid.points < options_.min_valid_ray_fraction * rays.size()) {
    std::ostringstream o;
    o << "laser plane " << PlaneText(plane_) << " is no laser plane of this camera: only "
      << grid.points << " of " << rays.size() << " image rays meet it validly (" << grid.parallel
      << " (nearly) parallel to it, " << grid.behind_camera << " meet it behind the camera, "
      << grid.out_of_range << " at depths outside [" << options_.min_depth_mm << ", "
      << options_.max_depth_mm
      << "] mm); check the plane's frame (sensor = camera frame), sign and units";
    throw InputError(o.str());
  }
  BuildTables();
}

// The ray-plane rule of core/ray_plane.hpp (IntersectRayPlane), inlined for the hot path on the
// ray r = (x, y, 1) and the unit plane (n, d): parallel when |n . r| < sin(min_ray_plane_angle)
// |r| (IntersectRayPlane's min_abs_cos = sin of the smallest ray-plane angle), behind when
// t = -d / (n . r) <= 0 (here w = 1/t = -(n . r) / d), and the point t r = (x z, y z, z) with
// z = t. On top of that rule the triangulator keeps only depths z in [min_depth_mm,
// max_depth_mm]. The fast path forms z as 1 / w instead of -d / (n . r): the same point to a few
// ulp (triangulator_test checks both paths against IntersectRayPlane).
Triangulator::Reject Triangulator::Classify(double x, double y) const {
  const double nr = plane_[0] * x + plane_[1] * y + plane_[2];
  if (nr * nr < sin2_min_ * (x * x + y * y + 1.0) || nr == 0.0) return Reject::kParallel;
  const double w = -nr / plane_[3];
  if (w <= 0) return Reject::kBehind;
  if (w < min_w_ || w > max_w_) return Reject::kOutOfRange;
  return Reject::kOk;
}

void Triangulator::Count(Reject r, TriangulationCounts& counts) {
  switch (r) {
    case Reject::kOk:
      ++counts.points;
      break;
    case Reject::kParallel:
      ++counts.parallel;
      break;
    case Reject::kBehind:
      ++counts.behind_camera;
      break;
    case Reject::kOutOfRange:
      ++counts.out_of_range;
      break;
  }
}

void Triangulator::BuildTables() {
  const int width = camera_.width_px();
  const int height = camera_.height_px();
  const double h = options_.lut_row_step_px;
  row_lo_ = -0.5;
  intervals_ = static_cast<int>(std::ceil(height / h));
  inv_step_ = 1.0 / h;
  const int knots = intervals_ + 1;
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(static_cast<std::size_t>(width) * knots);
  for (int u = 0; u < width; ++u) {
    for (int k = 0; k < knots; ++k) pixels.emplace_back(u, row_lo_ + k * h);
  }
  const std::vector<Eigen::Vector3d> rays = camera_.UnprojectMany(pixels);
  // Normalized coordinates and their exact row derivatives at the knots.
  std::vector<Eigen::Vector2d> value(rays.size()), slope(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Eigen::Vector3d& r = rays[i];
    if (!(r.z() > 1e-6)) {
      throw InputError("camera " + camera_.lensmodel() + ": the ray of pixel (" +
                       std::to_string(pixels[i].x()) + ", " + std::to_string(pixels[i].y()) +
                       ") points sideways or backwards (field of view >= 180 deg); the "
                       "triangulator's lookup tables need rays in front of the camera");
    }
    const Eigen::Vector3d p(r.x() / r.z(), r.y() / r.z(), 1.0);
    value[i] = p.head<2>();
    Eigen::Matrix<double, 2, 3> dq_dp;
    camera_.Project(p, &dq_dp, nullptr);
    // q(x, y, 1) = pixel: d(x, y)/dv = (dq/d(x, y))^-1 * (0, 1).
    const Eigen::Matrix2d a = dq_dp.leftCols<2>();
    slope[i] = a.inverse() * Eigen::Vector2d(0, 1);
  }
  table_.resize(static_cast<std::size_t>(width) * intervals_);
  for (int u = 0; u < width; ++u) {
    for (int k = 0; k < intervals_; ++k) {
      const std::size_t i0 = static_cast<std::size_t>(u) * knots + k;
      Cubic2& c = table_[static_cast<std::size_t>(u) * intervals_ + k];
      // Cubic Hermite on t in [0, 1]: values and slopes (times h) at both ends, as monomials.
      for (int a = 0; a < 2; ++a) {
        const double p0 = value[i0][a], p1 = value[i0 + 1][a];
        const double m0 = slope[i0][a] * h, m1 = slope[i0 + 1][a] * h;
        double* co = a == 0 ? c.x : c.y;
        co[0] = p0;
        co[1] = m0;
        co[2] = 3 * (p1 - p0) - 2 * m0 - m1;
        co[3] = 2 * (p0 - p1) + m0 + m1;
      }
    }
  }
}

Eigen::Vector3d Triangulator::TriangulateExact(double column, double row) const {
  if (!(column >= -0.5 && column <= camera_.width_px() - 0.5 && row >= -0.5 &&
        row <= camera_.height_px() - 0.5)) {
    return kNaNPoint;
  }
  const Eigen::Vector3d r = camera_.Unproject(Eigen::Vector2d(column, row));
  if (!(r.z() > 0)) return kNaNPoint;
  const double x = r.x() / r.z(), y = r.y() / r.z();
  if (Classify(x, y) != Reject::kOk) return kNaNPoint;
  const double z = -plane_[3] / (plane_[0] * x + plane_[1] * y + plane_[2]);
  return {x * z, y * z, z};
}

Eigen::Vector3d Triangulator::TriangulateFast(int column, double row) const {
  Eigen::Vector3d p;
  if (column < 0 || column >= camera_.width_px() || !(row >= -0.5) ||
      !(row <= camera_.height_px() - 0.5)) {
    return kNaNPoint;
  }
  const double s = (row - row_lo_) * inv_step_;
  const int k = std::min(static_cast<int>(s), intervals_ - 1);
  const double t = s - k;
  const Cubic2& c = table_[static_cast<std::size_t>(column) * intervals_ + k];
  const double x = c.x[0] + t * (c.x[1] + t * (c.x[2] + t * c.x[3]));
  const double y = c.y[0] + t * (c.y[1] + t * (c.y[2] + t * c.y[3]));
  if (Classify(x, y) != Reject::kOk) return kNaNPoint;
  const double z = -plane_[3] / (plane_[0] * x + plane_[1] * y + plane_[2]);
  p << x * z, y * z, z;
  return p;
}

TriangulationCounts Triangulator::Triangulate(std::span<const float> rows,
                                              std::uint32_t first_column,
                                              std::span<Eigen::Vector3d> points,
                                              TriangulationPath path) const {
  if (points.size() != rows.size()) {
    throw InputError("Triangulate: " + std::to_string(rows.size()) + " rows but room for " +
                     std::to_string(points.size()) + " points");
  }
  if (static_cast<std::uint64_t>(first_column) + rows.size() >
      static_cast<std::uint64_t>(camera_.width_px())) {
    throw InputError("Triangulate: columns " + std::to_string(first_column) + ".." +
                     std::to_string(first_column + rows.size()) + " exceed the camera's " +
                     std::to_string(camera_.width_px()) + " columns (profile of another sensor?)");
  }
  TriangulationCounts counts;
  const double hi = camera_.height_px() - 0.5;
  const std::size_t n = rows.size();
  if (path == TriangulationPath::kExact) {
    std::vector<Eigen::Vector2d> pixels;
    std::vector<std::size_t> index;
    pixels.reserve(n);
    index.reserve(n);
    for (std::size_t j = 0; j < n; ++j) {
      const double v = rows[j];
      points[j] = kNaNPoint;
      if (std::isnan(v)) {
        ++counts.no_peak;
      } else if (!(v >= row_lo_ && v <= hi)) {
        ++counts.outside_image;
      } else {
        pixels.emplace_back(static_cast<double>(first_column + j), v);
        index.push_back(j);
      }
    }
    const std::vector<Eigen::Vector3d> rays = camera_.UnprojectMany(pixels);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Eigen::Vector3d& r = rays[i];
      if (!(r.z() > 0)) {
        ++counts.behind_camera;
        continue;
      }
      const double x = r.x() / r.z(), y = r.y() / r.z();
      const Reject reject = Classify(x, y);
      Count(reject, counts);
      if (reject != Reject::kOk) continue;
      const double z = -plane_[3] / (plane_[0] * x + plane_[1] * y + plane_[2]);
      points[index[i]] = Eigen::Vector3d(x * z, y * z, z);
    }
    return counts;
  }
  // Fast path: the hot loop (bench/triangulation_benchmark.cpp).
  const double n0 = plane_[0], n1 = plane_[1], n2 = plane_[2];
  const double minus_inv_d = -1.0 / plane_[3];
  const double sin2 = sin2_min_, min_w = min_w_, max_w = max_w_, lo = row_lo_, inv_step = inv_step_;
  const int last = intervals_ - 1;
  const Cubic2* column_table = table_.data() + static_cast<std::size_t>(first_column) * intervals_;
  for (std::size_t j = 0; j < n; ++j, column_table += intervals_) {
    const double v = rows[j];
    if (!(v >= lo && v <= hi)) {
      points[j] = kNaNPoint;
      ++(std::isnan(v) ? counts.no_peak : counts.outside_image);
      continue;
    }
    const double s = (v - lo) * inv_step;
    const int k = std::min(static_cast<int>(s), last);
    const double t = s - k;
    const Cubic2& c = column_table[k];
    const double x = c.x[0] + t * (c.x[1] + t * (c.x[2] + t * c.x[3]));
    const double y = c.y[0] + t * (c.y[1] + t * (c.y[2] + t * c.y[3]));
    const double nr = n0 * x + n1 * y + n2;
    const double w = nr * minus_inv_d;
    if (!(w >= min_w && w <= max_w) || nr * nr < sin2 * (x * x + y * y + 1.0)) {
      points[j] = kNaNPoint;
      Count(Classify(x, y), counts);
      continue;
    }
    const double z = 1.0 / w;
    points[j] = Eigen::Vector3d(x * z, y * z, z);
    ++counts.points;
  }
  return counts;
}

}  // namespace lasercell::triangulation
