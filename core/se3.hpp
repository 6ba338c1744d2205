#pragma once
// SE(3) helpers. Conventions: transforms `target_from_source` as Eigen::Isometry3d; rotation
// vectors are axis * angle (rad); quaternions in files are unit (w, x, y, z); translations mm.
// Rotation distance is the angle of R_a^T R_b, in [0, pi], rad.
// QuaternionPose is a pose as files hold it (unit quaternion + translation, mm): the form in
// which the frame graph stores static edges and DhChain its mounting transforms, so that
// file -> memory -> file is exact.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <span>
#include <string>
#include <vector>

namespace lasercell {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Rotation vector (axis * angle, rad) -> unit quaternion. Exact for small angles too.
Eigen::Quaterniond QuaternionFromRotationVector(const Eigen::Vector3d& rotation_vector);
/// Unit quaternion -> rotation vector with angle in [0, pi].
Eigen::Vector3d RotationVectorFromQuaternion(const Eigen::Quaterniond& q);
/// Rotation matrix -> rotation vector with angle in [0, pi].
Eigen::Vector3d RotationVectorFromMatrix(const Eigen::Matrix3d& rotation);

/// Pose from rotation vector (rad) and translation (mm).
Eigen::Isometry3d PoseFromRotationVector(const Eigen::Vector3d& rotation_vector,
                                         const Eigen::Vector3d& translation_mm);
/// Pose from a unit quaternion and translation (mm).
Eigen::Isometry3d PoseFromQuaternion(const Eigen::Quaterniond& q,
                                     const Eigen::Vector3d& translation_mm);
/// [rotation vector (rad); translation (mm)] of a pose (the optimizer parametrisation).
Vector6d RotationVectorTranslation(const Eigen::Isometry3d& pose);
/// Inverse of RotationVectorTranslation.
Eigen::Isometry3d PoseFromRotationVectorTranslation(const Vector6d& v);

/// Angle of the relative rotation between a and b, rad, in [0, pi].
double RotationDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);
/// Angle of the relative rotation between the rotation parts of a and b, rad.
double RotationDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);
/// Distance between translations, mm.
double TranslationDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);

/// Weighted average of unit quaternions (Markley et al. 2007: principal eigenvector of
/// sum w_i q_i q_i^T), sign-invariant. Weights must be >= 0 with a positive sum.
Eigen::Quaterniond AverageQuaternions(std::span<const Eigen::Quaterniond> quaternions,
                                      std::span<const double> weights = {});
/// Weighted average pose: Markley rotation average, weighted mean translation.
Eigen::Isometry3d AveragePoses(std::span<const Eigen::Isometry3d> poses,
                               std::span<const double> weights = {});
/// Interpolates a -> b at t in [0, 1]: slerp of rotation, linear translation.
Eigen::Isometry3d InterpolatePoses(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                   double t);

/// Rotation R maximising trace(R^T H) for a cross-covariance H = sum w_i (t_i - t)(s_i - s)^T
/// (Umeyama 1991, eqs. 34-43, without scale): U S V^T from the SVD of H with the reflection guard
/// S = diag(1, 1, det(U V^T)). `singular_values` (optional) receives H's singular values, in
/// decreasing order (the second near zero: collinear points, the rotation about their line free).
Eigen::Matrix3d HornRotation(const Eigen::Matrix3d& cross_covariance,
                             Eigen::Vector3d* singular_values = nullptr);
/// Weighted closed-form rigid fit (Horn/Umeyama without scale): target_from_source minimising
/// sum w_i |t_i - (R s_i + t)|^2. Throws InputError for mismatched sizes, fewer than 3 points or
/// weights that do not sum to a positive number. Collinearity is not checked (callers that need
/// it test HornRotation's singular values or the points).
Eigen::Isometry3d HornRigidTransform(const std::vector<Eigen::Vector3d>& p_in_source,
                                     const std::vector<Eigen::Vector3d>& p_in_target,
                                     const std::vector<double>& weights = {});

/// Makes the rotation part orthonormal (nearest rotation by SVD). Used after arithmetic.
Eigen::Isometry3d Orthonormalized(const Eigen::Isometry3d& pose);

/// R = Rz(c) * Ry(b) * Rx(a) for xyz_deg = (a, b, c) in degrees: rotations about the fixed
/// base axes, x first (Fanuc's w p r, KUKA's C B A, the robot protocol's rx ry rz).
Eigen::Matrix3d RotationFromFixedXyzDeg(const Eigen::Vector3d& xyz_deg);
/// The angles (a, b, c) in degrees with R = Rz(c) * Ry(b) * Rx(a), b in [-90, 90], a and c in
/// (-180, 180]; at b = +-90 (gimbal lock) a = 0.
Eigen::Vector3d FixedXyzDegFromRotation(const Eigen::Matrix3d& rotation);

/// Skew-symmetric matrix [v]x so that [v]x w = v x w.
Eigen::Matrix3d Skew(const Eigen::Vector3d& v);

/// How far from 1 the norm of a stored quaternion may be (files, StaticEdge, DhChain mounts):
/// loose enough for a quaternion printed with 7 significant digits by a controller or a person,
/// tight enough to catch a typo. Matrices are built from the normalized quaternion.
inline constexpr double kUnitQuaternionTolerance = 1e-6;

/// The unit quaternion of a rotation matrix, with the canonical sign: the first nonzero of
/// (w, x, y, z) is positive (w >= 0; x > 0 when w == 0; ...), and no coefficient is -0.
Eigen::Quaterniond CanonicalQuaternion(const Eigen::Matrix3d& rotation);

/// A pose `target_from_source` as files hold it: p_in_target = R(rotation) * p_in_source +
/// translation_mm. The coefficients are kept exactly as given or read (never renormalized, any
/// sign), so writing them back reproduces the file; only ToIsometry normalizes, for the matrix.
/// Whoever stores one (StaticEdge, DhChain) checks it with CheckQuaternionPose.
struct QuaternionPose {
  /// Unit quaternion (|q| within kUnitQuaternionTolerance of 1); files write it (w, x, y, z).
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  /// The source frame's origin in target coordinates, mm.
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();

  /// The matrix, built from the normalized `rotation` exactly as PoseFromQuaternion builds it.
  Eigen::Isometry3d ToIsometry() const;
  /// One conversion of a rigid transform: CanonicalQuaternion(pose.linear()) and the
  /// translation as is. The rotation part must be orthonormal (see CheckRigidTransform).
  static QuaternionPose FromIsometry(const Eigen::Isometry3d& pose);
};

/// Throws InputError, starting with `what`, unless `pose` is finite with an orthonormal,
/// right-handed rotation (|R^T R - I| < 1e-9, det > 0), i.e. unless FromIsometry is faithful.
void CheckRigidTransform(const Eigen::Isometry3d& pose, const std::string& what);
/// Throws InputError, starting with `what`, unless `pose` is finite and |rotation| is within
/// kUnitQuaternionTolerance of 1.
void CheckQuaternionPose(const QuaternionPose& pose, const std::string& what);

}  // namespace lasercell
