#pragma once
// Ceres residuals of laser-plane fits (calib/laser_plane.hpp). The plane is n . p + d = 0 with
// the unit normal n (3 parameters on ceres::SphereManifold<3>) and the offset d (mm).

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <cmath>

namespace lasercell::calib {

/// Signed distance (mm) of a fixed 3-D point from the plane, times a weight:
/// r = w (n . p + d). Used for the stripe-on-chessboard method (Zhou & Zhang 2005), where the
/// points are stripe pixels' rays intersected with the board plane.
struct PlanePointDistanceCost {
  PlanePointDistanceCost(const Eigen::Vector3d& p_in_sensor, double weight)
      : p_(p_in_sensor), w_(weight) {}

  template <typename T>
  bool operator()(const T* normal, const T* offset, T* residual) const {
    residual[0] =
        T(w_) * (normal[0] * p_.x() + normal[1] * p_.y() + normal[2] * p_.z() + offset[0]);
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

/// The white-plane method (seed "Calibration chain" 2). The white plate's unit normal in the
/// sensor frame is m = m0 cos(a) + t sin(a): the given normal m0 (pointing towards the sensor),
/// tilted by the parameter a (rad) towards the unit direction t (t perpendicular to m0: the laser
/// line's direction on the plate, the one tilt the stripe images can observe). A pixel's unit ray
/// r (camera model) meets plate i, m . p = h - D0 (h: the plate's known height along m; D0: the
/// distance of the height-0 plate from the sensor origin, a parameter), at
/// p = r (h - D0) / (m . r); the residual is that point's weighted distance from the laser plane,
/// w (n . p + d). With w = 1 / |d(n . p + d)/d row| it is, to first order, the peak's row error
/// in px. Parameter blocks: normal (3), offset d (1), D0 (1), tilt a (1).
struct HeightPlaneRayCost {
  HeightPlaneRayCost(const Eigen::Vector3d& ray, const Eigen::Vector3d& white_normal,
                     const Eigen::Vector3d& tilt_direction, double height_mm, double weight)
      : r_(ray), m_(white_normal), t_(tilt_direction), h_(height_mm), w_(weight) {}

  template <typename T>
  bool operator()(const T* normal, const T* offset, const T* zero_distance, const T* tilt,
                  T* residual) const {
    using std::cos;
    using std::sin;
    const T mr = cos(tilt[0]) * T(m_.dot(r_)) + sin(tilt[0]) * T(t_.dot(r_));
    const T t = (T(h_) - zero_distance[0]) / mr;
    residual[0] =
        T(w_) * (t * (normal[0] * r_.x() + normal[1] * r_.y() + normal[2] * r_.z()) + offset[0]);
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& ray,
                                     const Eigen::Vector3d& white_normal,
                                     const Eigen::Vector3d& tilt_direction, double height_mm,
                                     double weight) {
    return new ceres::AutoDiffCostFunction<HeightPlaneRayCost, 1, 3, 1, 1, 1>(
        new HeightPlaneRayCost(ray, white_normal, tilt_direction, height_mm, weight));
  }

 private:
  Eigen::Vector3d r_;
  Eigen::Vector3d m_;
  Eigen::Vector3d t_;
  double h_;
  double w_;
};

}  // namespace lasercell::calib
