#pragma once
// First-order covariance algebra of rigid transforms, in the frame graph's convention
// (core/frame_graph.hpp): a pose T = target_from_source carries a 6x6 covariance over
// xi = [rotation vector (rad, 3); translation (mm, 3)] of a LEFT perturbation,
//   T_true = Exp(xi) * T,
// i.e. xi is expressed in the target frame. Exp is the SE(3) exponential (ExpSe3 below). To
// first order it agrees with PoseFromRotationVectorTranslation(xi) * T (rotation Exp(w) R,
// translation Exp(w) t + u), so covariances stated for either form are the same matrix.
//
// All propagation here is linear (first order, e.g. Barfoot & Furgale 2014, "Associating
// uncertainty with three-dimensional poses", IEEE T-RO 30(3), sec. III): it neglects terms of
// second order in xi, which are negligible while the rotational sigmas are small (below a few
// degrees) and the lever arms times the rotational sigma stay small against the translation
// sigmas' scale of interest. Inputs are assumed independent where a function says so.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/se3.hpp"

namespace lasercell {

/// SE(3) exponential of xi = [w (rad); u (mm)]: rotation Exp(w) (Rodrigues) and translation
/// V(w) u with V = I + (1 - cos a)/a^2 [w]x + (a - sin a)/a^3 [w]x^2, a = |w| (Barfoot 2017,
/// "State Estimation for Robotics", ch. 7). Exact for small angles (series near 0).
Eigen::Isometry3d ExpSe3(const Vector6d& xi);
/// Inverse of ExpSe3: [w; u] with |w| in [0, pi]. The rotation part must be orthonormal.
Vector6d LogSe3(const Eigen::Isometry3d& pose);

/// Adjoint of T = (R, t) for the [rotation; translation] ordering:
///   Ad(T) = [[R, 0], [[t]x R, R]],  so that  T * Exp(xi) * T^-1 = Exp(Ad(T) xi)  (exactly).
/// It moves a left perturbation across T: Exp(xi) T = T Exp(Ad(T^-1) xi).
Matrix6d Adjoint(const Eigen::Isometry3d& pose);

/// Covariance of c = a * b for independent a (cov_a, left perturbation in a's target frame) and
/// b (cov_b, left perturbation in b's target frame = a's source frame):
///   c_true = Exp(xa) a Exp(xb) b = Exp(xa) Exp(Ad(a) xb) c  =>  cov_c = cov_a + Ad(a) cov_b
///   Ad(a)^T
/// to first order (Barfoot & Furgale 2014, sec. III-A, independent factors).
Matrix6d ComposeCovariance(const Eigen::Isometry3d& a, const Matrix6d& cov_a,
                           const Matrix6d& cov_b);
/// Covariance of t^-1 given the covariance of t (both left perturbations):
///   t_true^-1 = t^-1 Exp(-xi) = Exp(-Ad(t^-1) xi) t^-1  =>  Ad(t^-1) cov Ad(t^-1)^T.
Matrix6d InverseCovariance(const Eigen::Isometry3d& pose, const Matrix6d& cov);
/// Covariance (mm^2) of the point q = t * p_in_child, p exact, t uncertain (cov, left
/// perturbation): q_true = Exp(xi) q ~ q + w x q + u, so J = [-[q]x, I] and cov_q = J cov J^T.
Eigen::Matrix3d PointCovariance(const Eigen::Isometry3d& pose, const Matrix6d& cov,
                                const Eigen::Vector3d& p_in_child);

/// 1-sigma per coordinate: sqrt of the diagonal, [rotation (rad, 3); translation (mm, 3)].
/// Diagonal entries below 0 (round-off) count as 0; NaN stays NaN.
Vector6d PoseSigma(const Matrix6d& cov);
/// 1-sigma of the rotation vector's components, degrees.
Eigen::Vector3d RotationSigmaDeg(const Matrix6d& cov);
/// 1-sigma of the translation components, mm.
Eigen::Vector3d TranslationSigmaMm(const Matrix6d& cov);

}  // namespace lasercell
