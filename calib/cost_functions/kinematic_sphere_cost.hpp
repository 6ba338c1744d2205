#pragma once
// Point-to-sphere residuals of laser points swept by a sensor on a robot (eye-in-hand laser
// calibration, joint-offset identification). One functor per profile: the robot's forward
// kinematics is evaluated once for the profile's joints, then every point of the profile is
// placed in the robot base and compared with its sphere:
//
//   p_in_base = base_from_flange(q; chain + delta) * flange_from_sensor * p_in_sensor
//   r_k       = (|p_in_base - c| - radius) / sigma
//
// Parameter blocks (all in one problem, Ceres may hold any of them constant):
//   robot   [4 n]  DH corrections added to the reference chain, in core's DhParameterVector
//                  order: joint offsets (rad), a (mm), d (mm), alpha (rad);
//   hand_eye [6]   [w; u] left perturbation of the reference flange_from_sensor X0:
//                  R = Exp(w) * R0, t = Exp(w) * t0 + u  (to first order Exp(xi) * X0, so a
//                  covariance over [w; u] at 0 is the frame graph's left-perturbation one);
//   centre  [3]    sphere centre in the robot base (mm);
//   radius  [1]    sphere radius (mm).
// Units mm and rad.

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <utility>
#include <vector>

#include "core/kinematics.hpp"

namespace lasercell::calib {

/// The fixed part of a 6-joint chain that KinematicSphereCost needs (reference DH rows and mounts).
struct KinematicChainReference {
  static constexpr int kJoints = 6;
  static constexpr int kParameters = 4 * kJoints;
  DhConvention convention = DhConvention::kStandard;
  std::array<double, kParameters> parameters{};  ///< DhParameterVector of the reference chain.
  std::array<double, kJoints> theta_offset_rad{};
  Eigen::Isometry3d base_from_chain = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d chain_from_flange = Eigen::Isometry3d::Identity();

  /// Copies a 6-joint DhChain (the caller checks the joint count).
  static KinematicChainReference From(const DhChain& chain) {
    KinematicChainReference ref;
    ref.convention = chain.convention();
    const std::vector<double> p = DhParameterVector(chain);
    for (int i = 0; i < kParameters; ++i) ref.parameters[i] = p[i];
    for (int i = 0; i < kJoints; ++i) ref.theta_offset_rad[i] = chain.joints()[i].theta_offset_rad;
    ref.base_from_chain = chain.base_from_chain();
    ref.chain_from_flange = chain.chain_from_flange();
    return ref;
  }

  /// base_from_flange as rotation R and translation t for joints q and corrections `delta`
  /// (kParameters values, DhParameterVector order), any scalar type.
  template <typename T>
  void BaseFromFlange(const double* q, const T* delta, Eigen::Matrix<T, 3, 3>* rotation,
                      Eigen::Matrix<T, 3, 1>* translation) const {
    constexpr int n = kJoints;
    Eigen::Matrix<T, 3, 3> r = base_from_chain.linear().cast<T>();
    Eigen::Matrix<T, 3, 1> t = base_from_chain.translation().cast<T>();
    Eigen::Matrix<T, 3, 3> link_r;
    Eigen::Matrix<T, 3, 1> link_t;
    for (int i = 0; i < n; ++i) {
      const T theta = T(q[i] + theta_offset_rad[i] + parameters[i]) + delta[i];
      const T a = T(parameters[n + i]) + delta[n + i];
      const T d = T(parameters[2 * n + i]) + delta[2 * n + i];
      const T alpha = T(parameters[3 * n + i]) + delta[3 * n + i];
      DhLinkRotationTranslation(convention, a, alpha, d, theta, &link_r, &link_t);
      t = t + r * link_t;
      r = r * link_r;
    }
    *translation = t + r * chain_from_flange.translation().cast<T>();
    *rotation = r * chain_from_flange.linear().cast<T>();
  }
};

/// Applies the hand-eye left perturbation [w; u] to X0 = (R0, t0): R = Exp(w) R0,
/// t = Exp(w) t0 + u.
template <typename T>
void PerturbedFlangeFromSensor(const Eigen::Isometry3d& reference, const T* w_u,
                               Eigen::Matrix<T, 3, 3>* rotation,
                               Eigen::Matrix<T, 3, 1>* translation) {
  T exp_w[9];
  ceres::AngleAxisToRotationMatrix(w_u, ceres::ColumnMajorAdapter3x3(exp_w));
  const Eigen::Map<const Eigen::Matrix<T, 3, 3>> e(exp_w);
  *rotation = e * reference.linear().cast<T>();
  *translation =
      e * reference.translation().cast<T>() + Eigen::Matrix<T, 3, 1>(w_u[3], w_u[4], w_u[5]);
}

/// Residuals of one profile's points against one sphere (see the file comment).
class KinematicSphereCost {
 public:
  /// `chain` and `flange_from_sensor_reference` must outlive the functor.
  KinematicSphereCost(const KinematicChainReference* chain,
                      const Eigen::Isometry3d* flange_from_sensor_reference,
                      std::array<double, KinematicChainReference::kJoints> joints_rad,
                      std::vector<Eigen::Vector3d> points_in_sensor, double sigma_mm)
      : chain_(chain),
        x0_(flange_from_sensor_reference),
        joints_(joints_rad),
        points_(std::move(points_in_sensor)),
        inv_sigma_(1.0 / sigma_mm) {}

  template <typename T>
  bool operator()(const T* robot, const T* hand_eye, const T* centre, const T* radius,
                  T* residuals) const {
    Eigen::Matrix<T, 3, 3> r_bf, r_fs;
    Eigen::Matrix<T, 3, 1> t_bf, t_fs;
    chain_->BaseFromFlange(joints_.data(), robot, &r_bf, &t_bf);
    PerturbedFlangeFromSensor(*x0_, hand_eye, &r_fs, &t_fs);
    const Eigen::Matrix<T, 3, 3> r = r_bf * r_fs;
    const Eigen::Matrix<T, 3, 1> t = r_bf * t_fs + t_bf;
    const Eigen::Matrix<T, 3, 1> c(centre[0], centre[1], centre[2]);
    const Eigen::Matrix<T, 3, 1> tc = t - c;
    for (std::size_t k = 0; k < points_.size(); ++k) {
      const Eigen::Matrix<T, 3, 1> v = r * points_[k].cast<T>() + tc;
      residuals[k] = (v.norm() - radius[0]) * T(inv_sigma_);
    }
    return true;
  }

  int num_residuals() const { return static_cast<int>(points_.size()); }

  /// The autodiff cost function (takes ownership of a copy of the functor).
  static ceres::CostFunction* Create(const KinematicChainReference* chain,
                                     const Eigen::Isometry3d* flange_from_sensor_reference,
                                     std::array<double, KinematicChainReference::kJoints> joints,
                                     std::vector<Eigen::Vector3d> points_in_sensor,
                                     double sigma_mm) {
    auto* functor = new KinematicSphereCost(chain, flange_from_sensor_reference, joints,
                                            std::move(points_in_sensor), sigma_mm);
    const int residuals = functor->num_residuals();
    return new ceres::AutoDiffCostFunction<KinematicSphereCost, ceres::DYNAMIC,
                                           KinematicChainReference::kParameters, 6, 3, 1>(
        functor, residuals);
  }

 private:
  const KinematicChainReference* chain_;
  const Eigen::Isometry3d* x0_;
  std::array<double, KinematicChainReference::kJoints> joints_;
  std::vector<Eigen::Vector3d> points_;
  double inv_sigma_;
};

/// Residual of a known sphere centre (e.g. from the half-sphere calibration) as a prior:
/// (c - c_known) / sigma, 3 residuals over the centre block.
struct KinematicCentrePrior {
  Eigen::Vector3d centre_known;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* centre, T* residuals) const {
    for (int i = 0; i < 3; ++i) residuals[i] = (centre[i] - T(centre_known[i])) * T(inv_sigma);
    return true;
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& centre_known, double sigma_mm) {
    return new ceres::AutoDiffCostFunction<KinematicCentrePrior, 3, 3>(
        new KinematicCentrePrior{centre_known, 1.0 / sigma_mm});
  }
};

}  // namespace lasercell::calib
