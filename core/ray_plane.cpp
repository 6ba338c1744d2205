#include "core/ray_plane.hpp"

#include <cmath>

namespace lasercell {

std::optional<Eigen::Vector3d> IntersectRayPlane(const Eigen::Vector3d& ray,
                                                 const Eigen::Vector3d& normal, double offset,
                                                 double min_abs_cos) {
  const double nr = normal.dot(ray);
  if (!(std::abs(nr) > min_abs_cos * normal.norm() * ray.norm())) return std::nullopt;
  const double t = -offset / nr;
  if (!(t > 0) || !std::isfinite(t)) return std::nullopt;
  return Eigen::Vector3d(t * ray);
}

}  // namespace lasercell
