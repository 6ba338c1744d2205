#pragma once
// Geometric point-to-sphere residual for Ceres: r = |p - c| - R (mm), signed, positive outside.
// Parameter blocks: centre c (3, mm), radius R (1, mm; held constant when the radius is known).
// Header-only; checked against numeric differences in tests/calib/sphere_fit_test.cpp.

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <cmath>

namespace lasercell::calib {

/// Signed distance of one measured point from the sphere surface.
struct SphereDistanceCost {
  explicit SphereDistanceCost(const Eigen::Vector3d& p_in_frame) : p_(p_in_frame) {}

  template <typename T>
  bool operator()(const T* center, const T* radius, T* residual) const {
    const T dx = T(p_.x()) - center[0];
    const T dy = T(p_.y()) - center[1];
    const T dz = T(p_.z()) - center[2];
    using std::sqrt;
    // A point exactly at the centre has no gradient; FitSphere never keeps such a point.
    residual[0] = sqrt(dx * dx + dy * dy + dz * dz) - radius[0];
    return true;
  }

  /// Autodiff cost (1 residual; centre 3, radius 1).
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_in_frame) {
    return new ceres::AutoDiffCostFunction<SphereDistanceCost, 1, 3, 1>(
        new SphereDistanceCost(p_in_frame));
  }

 private:
  Eigen::Vector3d p_;
};

}  // namespace lasercell::calib
