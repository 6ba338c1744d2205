#pragma once
// Ceres residuals of the joint stripe-on-chessboard refinement (Zhou & Zhang 2005, sec. 3.3):
// the laser plane and every board pose are estimated together from the board corners and the
// stripe pixels, so the plane's covariance carries the board-pose uncertainty. Board pose as
// camera_from_board = [angle-axis (3, rad); translation (3, mm)]; plane n . p + d = 0 (n on
// ceres::SphereManifold<3>).

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Core>

namespace lasercell::calib {

/// A board corner's reprojection error in normalized image coordinates (x/z, y/z of the
/// camera-model ray of the detected corner), times `scale` per axis (focal length in px / corner
/// sigma in px). Parameter block: pose (6).
struct BoardCornerCost {
  BoardCornerCost(const Eigen::Vector3d& corner_in_board, const Eigen::Vector2d& normalized,
                  const Eigen::Vector2d& scale)
      : x_(corner_in_board), q_(normalized), s_(scale) {}

  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    const T x[3] = {T(x_.x()), T(x_.y()), T(x_.z())};
    T p[3];
    ceres::AngleAxisRotatePoint(pose, x, p);
    for (int k = 0; k < 3; ++k) p[k] += pose[3 + k];
    residual[0] = T(s_.x()) * (p[0] / p[2] - T(q_.x()));
    residual[1] = T(s_.y()) * (p[1] / p[2] - T(q_.y()));
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& corner_in_board,
                                     const Eigen::Vector2d& normalized,
                                     const Eigen::Vector2d& scale) {
    return new ceres::AutoDiffCostFunction<BoardCornerCost, 2, 6>(
        new BoardCornerCost(corner_in_board, normalized, scale));
  }

 private:
  Eigen::Vector3d x_;
  Eigen::Vector2d q_;
  Eigen::Vector2d s_;
};

/// A stripe pixel's ray meets the board plane (z = 0 of the pose) at p; the residual is p's
/// weighted distance from the laser plane, w (n . p + d). Parameter blocks: normal (3),
/// offset (1), pose (6).
struct StripeOnBoardCost {
  StripeOnBoardCost(const Eigen::Vector3d& ray, double weight) : r_(ray), w_(weight) {}

  template <typename T>
  bool operator()(const T* normal, const T* offset, const T* pose, T* residual) const {
    const T z[3] = {T(0), T(0), T(1)};
    T m[3];
    ceres::AngleAxisRotatePoint(pose, z, m);
    const T mt = m[0] * pose[3] + m[1] * pose[4] + m[2] * pose[5];
    const T mr = m[0] * r_.x() + m[1] * r_.y() + m[2] * r_.z();
    const T s = mt / mr;
    residual[0] =
        T(w_) * (s * (normal[0] * r_.x() + normal[1] * r_.y() + normal[2] * r_.z()) + offset[0]);
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& ray, double weight) {
    return new ceres::AutoDiffCostFunction<StripeOnBoardCost, 1, 3, 1, 6>(
        new StripeOnBoardCost(ray, weight));
  }

 private:
  Eigen::Vector3d r_;
  double w_;
};

}  // namespace lasercell::calib
