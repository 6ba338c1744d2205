#pragma once
// Ray-plane intersection, the step of laser triangulation: a pixel's ray from the camera centre
// (the sensor frame's origin) meets the laser plane n . p + d = 0 (sensor frame, mm).

#include <Eigen/Core>
#include <optional>

namespace lasercell {

/// The point t * ray (t > 0) on the plane n . p + d = 0, `ray` from the origin in any length.
/// nullopt when the ray is parallel to the plane (|n . r| <= min_abs_cos * |n| |r|, i.e. the
/// ray within asin(min_abs_cos) of the plane) or the plane lies behind the origin.
std::optional<Eigen::Vector3d> IntersectRayPlane(const Eigen::Vector3d& ray,
                                                 const Eigen::Vector3d& normal, double offset,
                                                 double min_abs_cos = 1e-12);

}  // namespace lasercell
