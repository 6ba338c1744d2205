#pragma once
// Reprojection of a board corner into a mrcal camera, with analytic Jacobians: the lens part
// comes from mrcal_project's own gradients (CameraModel::ProjectWithIntrinsics), the rotation
// part from a 3-wide ceres::Jet through ceres::AngleAxisRotatePoint (exact, no finite
// differences).
//
//   p_in_board' = p_in_board + (0, 0, dz),  dz = k_x (1 - xr^2) + k_y (1 - yr^2),
//                 xr = 2 x / W - 1, yr = 2 y / H - 1   (board flatness: mrcal's calobject_warp
//                 idea, a paraboloid bow of the board; W x H is the corner grid extent, mm)
//   p_in_camera = R(r) p_in_board' + t          camera_from_board = [r (angle-axis, rad); t (mm)]
//   residual    = (project(p_in_camera; intrinsics) - observed_px) * weight       (px)
//
// Parameter blocks: [0] optimised intrinsics (IntrinsicsLayout::NumFree()), [1]
// camera_from_board (6), [2] warp (k_x, k_y in mm), present only when the cost is built with
// warp enabled.

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Core>
#include <vector>

#include "calib/camera_model.hpp"

namespace lasercell::calib {

/// How the optimised intrinsics block maps to mrcal's full vector (fx fy cx cy distortion...).
/// With fix_aspect the block is (f, cx, cy, distortion...) and fy = aspect * f.
struct IntrinsicsLayout {
  int num_full = 0;  ///< mrcal's intrinsics count for the lens model.
  bool fix_aspect = false;
  double aspect = 1.0;  ///< fy / fx when fix_aspect.

  int NumFree() const { return fix_aspect ? num_full - 1 : num_full; }
  void ToFull(const double* free, double* full) const {
    if (!fix_aspect) {
      for (int i = 0; i < num_full; ++i) full[i] = free[i];
      return;
    }
    full[0] = free[0];
    full[1] = aspect * free[0];
    for (int i = 2; i < num_full; ++i) full[i] = free[i - 1];
  }
  std::vector<double> FromFull(const std::vector<double>& full) const {
    if (!fix_aspect) return full;
    std::vector<double> free;
    free.push_back(full[0]);
    free.insert(free.end(), full.begin() + 2, full.end());
    return free;
  }
  /// Column c of d(full)/d(free) applied to a row of d/d(full): returns d/d(free[c]).
  double FreeDerivative(const double* d_dfull, int c) const {
    if (!fix_aspect) return d_dfull[c];
    if (c == 0) return d_dfull[0] + aspect * d_dfull[1];
    return d_dfull[c + 1];
  }
};

/// Paraboloid bow of the board at (x, y) in the board frame, per unit warp coefficient.
inline Eigen::Vector2d BoardWarpBasis(const Eigen::Vector3d& p_in_board,
                                      const Eigen::Vector2d& extent_mm) {
  const double xr = extent_mm.x() > 0 ? 2.0 * p_in_board.x() / extent_mm.x() - 1.0 : 0.0;
  const double yr = extent_mm.y() > 0 ? 2.0 * p_in_board.y() / extent_mm.y() - 1.0 : 0.0;
  return {1.0 - xr * xr, 1.0 - yr * yr};
}

class ReprojectionCost final : public ceres::CostFunction {
 public:
  /// `camera` (its lens model) must outlive the cost. warp: add the warp block.
  ReprojectionCost(const CameraModel* camera, const IntrinsicsLayout& layout,
                   const Eigen::Vector3d& p_in_board, const Eigen::Vector2d& observed_px, bool warp,
                   const Eigen::Vector2d& board_extent_mm, double weight = 1.0)
      : camera_(camera),
        layout_(layout),
        p_in_board_(p_in_board),
        observed_px_(observed_px),
        warp_(warp),
        warp_basis_(BoardWarpBasis(p_in_board, board_extent_mm)),
        weight_(weight) {
    set_num_residuals(2);
    mutable_parameter_block_sizes()->push_back(layout_.NumFree());
    mutable_parameter_block_sizes()->push_back(6);
    if (warp_) mutable_parameter_block_sizes()->push_back(2);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int n_full = layout_.num_full;
    const int n_free = layout_.NumFree();
    std::vector<double> full(n_full);
    layout_.ToFull(parameters[0], full.data());
    const double* rt = parameters[1];
    double dz = 0;
    if (warp_) dz = parameters[2][0] * warp_basis_.x() + parameters[2][1] * warp_basis_.y();

    using Jet3 = ceres::Jet<double, 3>;
    const Jet3 r[3] = {Jet3(rt[0], 0), Jet3(rt[1], 1), Jet3(rt[2], 2)};
    const Jet3 pb[3] = {Jet3(p_in_board_.x()), Jet3(p_in_board_.y()), Jet3(p_in_board_.z() + dz)};
    Jet3 pr[3];
    ceres::AngleAxisRotatePoint(r, pb, pr);
    const Eigen::Vector3d p_in_camera(pr[0].a + rt[3], pr[1].a + rt[4], pr[2].a + rt[5]);
    if (!(p_in_camera.z() > 0)) return false;  // behind the camera: reject the step

    const bool want_intr = jacobians != nullptr && jacobians[0] != nullptr;
    const bool want_pose = jacobians != nullptr && jacobians[1] != nullptr;
    const bool want_warp = warp_ && jacobians != nullptr && jacobians[2] != nullptr;
    Eigen::Matrix<double, 2, 3> dq_dp;
    std::vector<double> dq_dfull;
    if (want_intr) dq_dfull.resize(2 * n_full);
    Eigen::Vector2d q;
    try {
      q = camera_->ProjectWithIntrinsics(full.data(), p_in_camera,
                                         (want_pose || want_warp) ? &dq_dp : nullptr,
                                         want_intr ? dq_dfull.data() : nullptr);
    } catch (const std::exception&) {
      return false;
    }
    residuals[0] = weight_ * (q.x() - observed_px_.x());
    residuals[1] = weight_ * (q.y() - observed_px_.y());
    if (!std::isfinite(residuals[0]) || !std::isfinite(residuals[1])) return false;

    if (want_intr) {
      for (int row = 0; row < 2; ++row) {
        for (int c = 0; c < n_free; ++c) {
          jacobians[0][row * n_free + c] =
              weight_ * layout_.FreeDerivative(&dq_dfull[row * n_full], c);
        }
      }
    }
    if (want_pose) {
      Eigen::Matrix3d dp_dr;
      for (int i = 0; i < 3; ++i) dp_dr.row(i) = pr[i].v.transpose();
      const Eigen::Matrix<double, 2, 3> dq_dr = dq_dp * dp_dr;
      for (int row = 0; row < 2; ++row) {
        for (int c = 0; c < 3; ++c) {
          jacobians[1][row * 6 + c] = weight_ * dq_dr(row, c);
          jacobians[1][row * 6 + 3 + c] = weight_ * dq_dp(row, c);
        }
      }
    }
    if (want_warp) {
      double R[9];  // column-major
      ceres::AngleAxisToRotationMatrix(rt, R);
      const Eigen::Vector3d rz(R[6], R[7], R[8]);  // d p_in_camera / d dz
      const Eigen::Vector2d dq_ddz = dq_dp * rz;
      for (int row = 0; row < 2; ++row) {
        jacobians[2][row * 2 + 0] = weight_ * dq_ddz(row) * warp_basis_.x();
        jacobians[2][row * 2 + 1] = weight_ * dq_ddz(row) * warp_basis_.y();
      }
    }
    return true;
  }

 private:
  const CameraModel* camera_;
  IntrinsicsLayout layout_;
  Eigen::Vector3d p_in_board_;
  Eigen::Vector2d observed_px_;
  bool warp_;
  Eigen::Vector2d warp_basis_;
  double weight_;
};

/// Linear residuals A * x over one parameter block (regularisation of splined lens models:
/// knot values and their second differences). Jacobian = A.
class LinearRegularizationCost final : public ceres::CostFunction {
 public:
  explicit LinearRegularizationCost(Eigen::MatrixXd a) : a_(std::move(a)) {
    set_num_residuals(static_cast<int>(a_.rows()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(a_.cols()));
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::VectorXd> x(parameters[0], a_.cols());
    Eigen::Map<Eigen::VectorXd>(residuals, a_.rows()) = a_ * x;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          jacobians[0], a_.rows(), a_.cols()) = a_;
    }
    return true;
  }

 private:
  Eigen::MatrixXd a_;
};

}  // namespace lasercell::calib
