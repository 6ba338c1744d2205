#pragma once
// Serial-robot kinematics vocabulary shared by the frame graph (core), the calibration solvers
// (calib) and the simulator (datasets). Units: mm and rad. Joint values in rad.
// `BaseFromFlange(joints)` returns base_from_flange: p_in_base = T * p_in_flange.
//
// Denavit-Hartenberg conventions:
//  - kStandard (Denavit & Hartenberg 1955, as in UR's published tables):
//      T_i = RotZ(theta_i) * TransZ(d_i) * TransX(a_i) * RotX(alpha_i)
//  - kModified (Craig 1986):
//      T_i = RotX(alpha_{i-1}) * TransX(a_{i-1}) * RotZ(theta_i) * TransZ(d_i)
//    (row i stores alpha_{i-1} and a_{i-1} in alpha_rad and a_mm).
//  theta_i = joint_i + theta_offset_rad_i (nominal zero) + joint_offset_rad_i (calibrated error).
// base_from_chain and chain_from_flange are fixed transforms before and after the chain
// (identity by default); they let a calibrated model absorb mounting errors. DhChain stores them
// as files hold them (QuaternionPose: unit quaternion + translation, mm), so a chain read from
// cell.yaml writes back the very same numbers; their matrices are computed once, when set.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/se3.hpp"

namespace lasercell {

/// Interface of a robot's forward kinematics, as the frame graph uses it.
class KinematicModel {
 public:
  virtual ~KinematicModel() = default;
  /// Number of joint values BaseFromFlange expects.
  virtual int NumJoints() const = 0;
  /// base_from_flange for the given joint values (rad). Throws InputError on a wrong count or
  /// non-finite values.
  virtual Eigen::Isometry3d BaseFromFlange(std::span<const double> joints_rad) const = 0;
  /// A deep copy.
  virtual std::unique_ptr<KinematicModel> Clone() const = 0;
  /// Short type name used in files, e.g. "dh".
  virtual std::string TypeName() const = 0;
};

/// Which DH convention a chain uses.
enum class DhConvention { kStandard, kModified };

/// One row of a DH table.
struct DhJoint {
  double a_mm = 0;              ///< Link length (kModified: a_{i-1}), mm.
  double alpha_rad = 0;         ///< Link twist (kModified: alpha_{i-1}), rad.
  double d_mm = 0;              ///< Link offset, mm.
  double theta_offset_rad = 0;  ///< Nominal joint zero offset, rad.
  double joint_offset_rad = 0;  ///< Calibrated joint offset error, rad (0 when nominal).
};

/// A serial chain described by a DH table, with base and flange transforms (mounts).
/// Mounts are stored as QuaternionPose (the `*_stored()` getters); `base_from_chain()` and
/// `chain_from_flange()` return the matrices built from them (QuaternionPose::ToIsometry),
/// cached when the mount is set, so BaseFromFlange converts nothing.
class DhChain final : public KinematicModel {
 public:
  DhChain() = default;
  /// Mounts given as matrices are converted once (QuaternionPose::FromIsometry). Throws
  /// InputError for a non-finite DH value or a mount that is not a finite rigid transform.
  DhChain(DhConvention convention, std::vector<DhJoint> joints,
          const Eigen::Isometry3d& base_from_chain = Eigen::Isometry3d::Identity(),
          const Eigen::Isometry3d& chain_from_flange = Eigen::Isometry3d::Identity());
  /// Mounts stored exactly as given (e.g. as read from a file). Throws InputError for a
  /// non-finite DH value or a mount failing CheckQuaternionPose.
  DhChain(DhConvention convention, std::vector<DhJoint> joints,
          const QuaternionPose& base_from_chain, const QuaternionPose& chain_from_flange);

  int NumJoints() const override { return static_cast<int>(joints_.size()); }
  Eigen::Isometry3d BaseFromFlange(std::span<const double> joints_rad) const override;
  std::unique_ptr<KinematicModel> Clone() const override;
  std::string TypeName() const override { return "dh"; }

  /// base_from_link_i for i = 1..n (element i-1), useful for Jacobians and drawing.
  std::vector<Eigen::Isometry3d> LinkPoses(std::span<const double> joints_rad) const;

  DhConvention convention() const { return convention_; }
  const std::vector<DhJoint>& joints() const { return joints_; }
  std::vector<DhJoint>& mutable_joints() { return joints_; }

  /// The mounts as matrices: exactly `*_stored().ToIsometry()`, computed when set.
  const Eigen::Isometry3d& base_from_chain() const { return base_from_chain_matrix_; }
  const Eigen::Isometry3d& chain_from_flange() const { return chain_from_flange_matrix_; }
  /// The mounts as stored: quaternion and translation (mm), as given or read.
  const QuaternionPose& base_from_chain_stored() const { return base_from_chain_; }
  const QuaternionPose& chain_from_flange_stored() const { return chain_from_flange_; }
  /// Sets a mount from a matrix, converted once (QuaternionPose::FromIsometry). Throws
  /// InputError (and keeps the previous mount) unless it is a finite rigid transform.
  void set_base_from_chain(const Eigen::Isometry3d& base_from_chain);
  void set_chain_from_flange(const Eigen::Isometry3d& chain_from_flange);
  /// Sets a mount exactly as given. Throws InputError (and keeps the previous mount) unless it
  /// passes CheckQuaternionPose.
  void set_base_from_chain(const QuaternionPose& base_from_chain);
  void set_chain_from_flange(const QuaternionPose& chain_from_flange);

 private:
  DhConvention convention_ = DhConvention::kStandard;
  std::vector<DhJoint> joints_;
  QuaternionPose base_from_chain_;
  QuaternionPose chain_from_flange_;
  // base_from_chain_.ToIsometry() and chain_from_flange_.ToIsometry(), kept in step by the
  // constructors and setters (BaseFromFlange runs in calibration's inner loops).
  Eigen::Isometry3d base_from_chain_matrix_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d chain_from_flange_matrix_ = Eigen::Isometry3d::Identity();
};

/// Which DH quantity a calibration parameter of a chain adjusts (see DhParameterVector).
enum class DhParameterKind { kJointOffset, kA, kD, kAlpha };

/// Number of calibration parameters of an n-joint chain: 4 n (joint offset, a, d, alpha per
/// joint), in the order of DhParameterVector.
inline int NumDhParameters(int joints) { return 4 * joints; }
/// Kind of calibration parameter `index` (0 <= index < 4 n) of an n-joint chain: indices
/// [0, n) joint offsets, [n, 2n) a, [2n, 3n) d, [3n, 4n) alpha; joint = index % n.
DhParameterKind DhParameterKindAt(int index, int joints);
/// Name of calibration parameter `index`, e.g. "joint_offset_1" (rad), "a_2" (mm), "d_4" (mm),
/// "alpha_6" (rad); joints counted from 1.
std::string DhParameterName(int index, int joints);
/// The chain's calibration parameters as one vector of length 4 n: joint_offset_rad of every
/// joint, then a_mm, d_mm, alpha_rad (theta_offset_rad, the nominal zero, is not a parameter).
std::vector<double> DhParameterVector(const DhChain& chain);
/// A copy of `chain` with its calibration parameters replaced by `parameters` (length 4 n,
/// order of DhParameterVector); mounts and theta_offset_rad are kept. Throws InputError for a
/// wrong length or non-finite values.
DhChain WithDhParameters(const DhChain& chain, std::span<const double> parameters);

/// link_{i-1}_from_link_i of one DH row as rotation and translation, for any scalar type (the
/// calibration solvers evaluate it with automatic-differentiation jets). Same closed forms as
/// DhChain::BaseFromFlange (Spong et al. 2006, eq. 3.10; Craig 1986, eq. 3.6).
template <typename T>
void DhLinkRotationTranslation(DhConvention convention, const T& a_mm, const T& alpha_rad,
                               const T& d_mm, const T& theta_rad, Eigen::Matrix<T, 3, 3>* rotation,
                               Eigen::Matrix<T, 3, 1>* translation) {
  using std::cos;
  using std::sin;
  const T ct = cos(theta_rad), st = sin(theta_rad), ca = cos(alpha_rad), sa = sin(alpha_rad);
  const T zero(0);
  if (convention == DhConvention::kStandard) {
    // clang-format off
    *rotation << ct, -st * ca,  st * sa,
                 st,  ct * ca, -ct * sa,
                 zero, sa,      ca;
    // clang-format on
    *translation << a_mm * ct, a_mm * st, d_mm;
  } else {
    // clang-format off
    *rotation << ct,      -st,      zero,
                 st * ca,  ct * ca, -sa,
                 st * sa,  ct * sa,  ca;
    // clang-format on
    *translation << a_mm, -sa * d_mm, ca * d_mm;
  }
}

/// Nominal UR5 (Universal Robots' published standard-DH table, mm):
/// d1 = 89.159, a2 = -425, a3 = -392.25, d4 = 109.15, d5 = 94.65, d6 = 82.3,
/// alpha = (pi/2, 0, 0, pi/2, -pi/2, 0).
DhChain NominalUr5();

}  // namespace lasercell
