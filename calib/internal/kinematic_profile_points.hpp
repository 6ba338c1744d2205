#pragma once
// Private, minimal triangulation for the robot-sphere calibrations (tests and the CLI): each
// profile column's peak row -> pixel ray (CameraModel::UnprojectMany) -> intersection with the
// laser plane n . p + d = 0 (sensor frame, mm). The triangulation module owns the real one
// (peak selection, ROI, timing); this only turns peaks into points, exactly.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "calib/camera_model.hpp"

namespace lasercell::calib::internal {

/// Points in the sensor frame of one profile's valid peaks (NaN rows skipped); rays hitting the
/// plane at a grazing angle or behind the camera are skipped.
inline std::vector<Eigen::Vector3d> ProfilePointsOnPlane(const CameraModel& camera,
                                                         const Eigen::Vector4d& plane,
                                                         std::uint32_t first_column,
                                                         const std::vector<float>& row_px) {
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(row_px.size());
  for (std::size_t j = 0; j < row_px.size(); ++j) {
    if (std::isfinite(row_px[j])) {
      pixels.emplace_back(static_cast<double>(first_column + j), static_cast<double>(row_px[j]));
    }
  }
  std::vector<Eigen::Vector3d> points;
  if (pixels.empty()) return points;
  const std::vector<Eigen::Vector3d> rays = camera.UnprojectMany(pixels);
  points.reserve(rays.size());
  const Eigen::Vector3d n = plane.head<3>();
  for (const Eigen::Vector3d& ray : rays) {
    const double denom = n.dot(ray);
    if (std::abs(denom) < 1e-6) continue;
    const double t = -plane[3] / denom;
    if (!(t > 0) || !std::isfinite(t)) continue;
    points.push_back(t * ray);
  }
  return points;
}

}  // namespace lasercell::calib::internal
