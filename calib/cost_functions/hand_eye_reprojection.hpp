#pragma once
// Reprojection cost of one chessboard corner in the robot-world-hand-eye problem (hand_eye.hpp):
//   p_in_camera = X^-1 * A_i^-1 * Y * p_in_board,   residual = project(p_in_camera) - detected
// with X = flange_from_camera and Y = base_from_board perturbed around fixed estimates:
//   R = Exp(d[0..2]) * R_est (left, rotation vector rad), t = t_est + d[3..5] (mm).
// Projection goes through the mrcal CameraModel with its analytic dq/dp, chained into Ceres
// Jets, so the functor works with ceres::AutoDiffCostFunction<..., 2, 6, 6>.

#include <ceres/jet.h>
#include <ceres/rotation.h>

#include <Eigen/Geometry>

#include "calib/camera_model.hpp"

namespace lasercell::calib {

/// Projects a point through `camera` (fixed intrinsics): double version.
inline void ProjectThroughCamera(const CameraModel& camera, const double p[3], double q[2]) {
  const Eigen::Vector2d pix = camera.ProjectWithIntrinsics(
      camera.intrinsics().data(), Eigen::Vector3d(p[0], p[1], p[2]), nullptr, nullptr);
  q[0] = pix.x();
  q[1] = pix.y();
}

/// Jet version: value from mrcal, derivative = dq/dp * dp (chain rule).
template <typename T, int N>
void ProjectThroughCamera(const CameraModel& camera, const ceres::Jet<T, N> p[3],
                          ceres::Jet<T, N> q[2]) {
  Eigen::Matrix<double, 2, 3> dq_dp;
  const Eigen::Vector2d pix = camera.ProjectWithIntrinsics(
      camera.intrinsics().data(), Eigen::Vector3d(p[0].a, p[1].a, p[2].a), &dq_dp, nullptr);
  for (int r = 0; r < 2; ++r) {
    q[r].a = pix[r];
    q[r].v = dq_dp(r, 0) * p[0].v + dq_dp(r, 1) * p[1].v + dq_dp(r, 2) * p[2].v;
  }
}

/// One corner's residual (2, px) over the perturbations of X (6) and Y (6).
class HandEyeReprojectionCost {
 public:
  /// `camera` must outlive the functor.
  HandEyeReprojectionCost(const CameraModel& camera, const Eigen::Isometry3d& base_from_flange,
                          const Eigen::Isometry3d& flange_from_camera_est,
                          const Eigen::Isometry3d& base_from_board_est,
                          const Eigen::Vector3d& p_in_board, const Eigen::Vector2d& detected_px)
      : camera_(camera),
        flange_from_base_(base_from_flange.inverse()),
        x_est_(flange_from_camera_est),
        p_rotated_in_base_(base_from_board_est.linear() * p_in_board),
        y_translation_(base_from_board_est.translation()),
        detected_px_(detected_px) {}

  template <typename T>
  bool operator()(const T* dx, const T* dy, T* residual) const {
    // Y * p = Exp(dy_r) (R_Y p) + t_Y + dy_t.
    const T rotated[3] = {T(p_rotated_in_base_.x()), T(p_rotated_in_base_.y()),
                          T(p_rotated_in_base_.z())};
    T p_base[3];
    ceres::AngleAxisRotatePoint(dy, rotated, p_base);
    for (int k = 0; k < 3; ++k) p_base[k] += T(y_translation_[k]) + dy[3 + k];
    // A^-1 (constant).
    T p_flange[3];
    for (int r = 0; r < 3; ++r) {
      p_flange[r] = T(flange_from_base_.translation()[r]);
      for (int c = 0; c < 3; ++c) p_flange[r] += T(flange_from_base_.linear()(r, c)) * p_base[c];
    }
    // X^-1 v = R_est^T Exp(-dx_r) (v - t_est - dx_t).
    T v[3];
    for (int k = 0; k < 3; ++k) v[k] = p_flange[k] - T(x_est_.translation()[k]) - dx[3 + k];
    const T minus_dr[3] = {-dx[0], -dx[1], -dx[2]};
    T w[3];
    ceres::AngleAxisRotatePoint(minus_dr, v, w);
    T p_camera[3];
    for (int r = 0; r < 3; ++r) {
      p_camera[r] = T(0);
      for (int c = 0; c < 3; ++c) p_camera[r] += T(x_est_.linear()(c, r)) * w[c];
    }
    T q[2];
    ProjectThroughCamera(camera_, p_camera, q);
    residual[0] = q[0] - T(detected_px_.x());
    residual[1] = q[1] - T(detected_px_.y());
    return true;
  }

 private:
  const CameraModel& camera_;
  Eigen::Isometry3d flange_from_base_;
  Eigen::Isometry3d x_est_;
  Eigen::Vector3d p_rotated_in_base_;
  Eigen::Vector3d y_translation_;
  Eigen::Vector2d detected_px_;
};

/// One corner's residual (2, px) over a perturbation (6) of camera_from_board, for per-view PnP
/// refinement: p_in_camera = Exp(d_r) R_est p + t_est + d_t.
class BoardPoseReprojectionCost {
 public:
  BoardPoseReprojectionCost(const CameraModel& camera, const Eigen::Isometry3d& camera_from_board,
                            const Eigen::Vector3d& p_in_board, const Eigen::Vector2d& detected_px)
      : camera_(camera),
        rotated_(camera_from_board.linear() * p_in_board),
        translation_(camera_from_board.translation()),
        detected_px_(detected_px) {}

  template <typename T>
  bool operator()(const T* d, T* residual) const {
    const T rotated[3] = {T(rotated_.x()), T(rotated_.y()), T(rotated_.z())};
    T p[3];
    ceres::AngleAxisRotatePoint(d, rotated, p);
    for (int k = 0; k < 3; ++k) p[k] += T(translation_[k]) + d[3 + k];
    T q[2];
    ProjectThroughCamera(camera_, p, q);
    residual[0] = q[0] - T(detected_px_.x());
    residual[1] = q[1] - T(detected_px_.y());
    return true;
  }

 private:
  const CameraModel& camera_;
  Eigen::Vector3d rotated_;
  Eigen::Vector3d translation_;
  Eigen::Vector2d detected_px_;
};

}  // namespace lasercell::calib
