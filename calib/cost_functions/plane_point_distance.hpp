#pragma once
// Ceres residuals of laser-plane fits (calib/laser_plane.hpp). The plane is n . p + d = 0 with
// the unit normal n (3 parameters on ceres::SphereManifold<3>) and the offset d (mm).

#include <ceres/ceres.h>

#include <Eigen/Core>

namespace lasercell::calib {

/// Signed distance (mm) of a fixed 3-D point from the plane, times a weight:
/// r = w (n . p + d). Used for the stripe-on-chessboard method (Zhou & Zhang 2005), where the
/// points are stripe pixels' rays intersected with the board plane.
struct PlanePointDistanceCost {
  PlanePointDistanceCost(const Eigen::Vector3d& p_in_sensor, double weight)
      : p_(p_in_sensor), w_(weight) {}

  template <typename T>
  bool operator()(const T* normal, const T* offset, T* residual) const {
    residual[0] = T(w_) * (normal[0] * p_.x() + normal[1] * p_.y() + normal[2] * p_.z() + offset[0]);
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& p_in_sensor, double weight = 1.0) {
    return new ceres::AutoDiffCostFunction<PlanePointDistanceCost, 1, 3, 1>(
        new PlanePointDistanceCost(p_in_sensor, weight));
  }

 private:
  Eigen::Vector3d p_;
  double w_;
};

/// The white-plane method (seed "Calibration chain" 2). A pixel's unit ray r (camera model)
/// meets the white plane m . p = h - D0 (m: the white plane's unit normal in the sensor frame,
/// pointing towards the sensor, known; h: the plane's known height along m; D0: the distance of
/// the height-0 plane from the sensor origin, a parameter) at p = r (h - D0) / (m . r); the
/// residual is that point's weighted distance from the laser plane, r = w (n . p + d). With w =
/// 1 / |d(n . p + d)/d row| the residual is, to first order, the peak's row error in px.
struct HeightPlaneRayCost {
  HeightPlaneRayCost(const Eigen::Vector3d& ray, const Eigen::Vector3d& white_normal,
                     double height_mm, double weight)
      : r_(ray), m_(white_normal), h_(height_mm), w_(weight) {}

  template <typename T>
  bool operator()(const T* normal, const T* offset, const T* zero_distance, T* residual) const {
    const double mr = m_.dot(r_);
    const T t = (T(h_) - zero_distance[0]) / T(mr);
    residual[0] =
        T(w_) * (t * (normal[0] * r_.x() + normal[1] * r_.y() + normal[2] * r_.z()) + offset[0]);
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& ray, const Eigen::Vector3d& white_normal,
                                     double height_mm, double weight) {
    return new ceres::AutoDiffCostFunction<HeightPlaneRayCost, 1, 3, 1, 1>(
        new HeightPlaneRayCost(ray, white_normal, height_mm, weight));
  }

 private:
  Eigen::Vector3d r_;
  Eigen::Vector3d m_;
  double h_;
  double w_;
};

}  // namespace lasercell::calib
