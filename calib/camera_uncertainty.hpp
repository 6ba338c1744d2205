#pragma once
// What a calibrated camera's own uncertainty does to a quantity computed through it.
//
// A camera calibrated from board views knows its intrinsics only to their covariance Sigma
// (CameraModel::intrinsics_covariance). Everything measured through the camera afterwards - a
// laser plane, the spheres of a sensor-to-robot fit - inherits that error, and it is shared by
// every point measured with the camera, so no amount of data downstream averages it away. A
// downstream fit's own covariance (from its residuals) holds only its own noise.
//
// First-order propagation by central differences along the principal axes of Sigma: with
// Sigma = sum_k lambda_k v_k v_k^T and s_k = h sqrt(lambda_k) v_k,
//   d_k = (f(c + s_k) - f(c - s_k)) / (2 h),   cov f = sum_k d_k d_k^T  (= J Sigma J^T),
// which needs no derivative of f (f may be a whole solver); 2 N evaluations of f for N
// intrinsics with a non-zero variance. h = kPropagationStep < 1: a rational lens model's
// strongly correlated distortion terms, moved a full sigma along their principal axis, can fold
// over at the imager's edge where the calibrated model does not.

#include <Eigen/Core>
#include <functional>
#include <string>

#include "calib/camera_model.hpp"

namespace lasercell::calib {

/// Models with more intrinsics than this (splined models) are not propagated: 2 N re-solves of
/// a downstream calibration would take too long; callers say so in their warnings.
constexpr int kMaxPropagatedIntrinsics = 40;
/// The central differences' step h, in sigmas along each principal axis.
constexpr double kPropagationStep = 0.1;

/// Why the camera's covariance cannot be propagated ("" when it can): none stored, or too many
/// intrinsics.
std::string CameraPropagationProblem(const CameraModel& camera);

/// The propagation along each principal axis kept apart: column k of `intrinsics_steps` is the
/// +1-sigma step s_k / h of the intrinsics (lens model's order), column k of `responses` the
/// matching d_k = df at that step. responses * responses^T is the covariance.
struct IntrinsicsAxes {
  Eigen::MatrixXd intrinsics_steps;  ///< NumIntrinsics() x K.
  Eigen::MatrixXd responses;         ///< f's size x K.
};

/// PropagateIntrinsicsCovariance, axis by axis (the same evaluations of f).
IntrinsicsAxes PropagateIntrinsicsAxes(const CameraModel& camera,
                                       const std::function<Eigen::VectorXd(const CameraModel&)>& f);

/// Covariance of f(camera) caused by camera.intrinsics_covariance() (see the file comment). f
/// returns the same number of values for every camera it is given; it is called with copies of
/// `camera` whose intrinsics are perturbed (and whose covariance is cleared). Throws InputError
/// when CameraPropagationProblem(camera) is not empty, and what f throws.
Eigen::MatrixXd PropagateIntrinsicsCovariance(
    const CameraModel& camera, const std::function<Eigen::VectorXd(const CameraModel&)>& f);

}  // namespace lasercell::calib
