#include "calib/camera_uncertainty.hpp"

#include <Eigen/Eigenvalues>
#include <vector>

#include "core/error.hpp"

namespace lasercell::calib {

std::string CameraPropagationProblem(const CameraModel& camera) {
  if (camera.intrinsics_covariance().size() == 0) {
    return "the camera model carries no intrinsics covariance (calibrate it with lasercell, "
           "or the camera's uncertainty is not included)";
  }
  if (camera.NumIntrinsics() > kMaxPropagatedIntrinsics) {
    return "the camera's " + std::to_string(camera.NumIntrinsics()) +
           " intrinsics are too many to propagate (at most " +
           std::to_string(kMaxPropagatedIntrinsics) + ")";
  }
  return "";
}

IntrinsicsAxes PropagateIntrinsicsAxes(
    const CameraModel& camera, const std::function<Eigen::VectorXd(const CameraModel&)>& f) {
  if (const std::string problem = CameraPropagationProblem(camera); !problem.empty()) {
    throw InputError("cannot propagate the camera's uncertainty: " + problem);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(camera.intrinsics_covariance());
  const Eigen::VectorXd lambda = eigen.eigenvalues();
  const double largest = lambda.maxCoeff();
  const std::vector<double> base = camera.intrinsics();
  const auto evaluate = [&](const Eigen::VectorXd& step) {
    std::vector<double> values = base;
    for (std::size_t i = 0; i < values.size(); ++i) values[i] += step(static_cast<Eigen::Index>(i));
    return f(CameraModel(camera.lensmodel(), values, camera.width_px(), camera.height_px()));
  };
  std::vector<Eigen::VectorXd> steps, responses;
  for (Eigen::Index k = 0; k < lambda.size(); ++k) {
    // Directions of (numerically) zero variance: a fixed parameter, fy tied to fx.
    if (!(lambda(k) > 1e-14 * largest)) continue;
    const Eigen::VectorXd sigma_step = std::sqrt(lambda(k)) * eigen.eigenvectors().col(k);
    const Eigen::VectorXd step = kPropagationStep * sigma_step;
    responses.push_back((0.5 / kPropagationStep) * (evaluate(step) - evaluate(-step)));
    LASERCELL_CHECK(responses.back().size() == responses.front().size(),
                    "the propagated function changed its output size");
    steps.push_back(sigma_step);
  }
  IntrinsicsAxes axes;
  const auto k = static_cast<Eigen::Index>(steps.size());
  axes.intrinsics_steps = Eigen::MatrixXd::Zero(lambda.size(), k);
  axes.responses = Eigen::MatrixXd::Zero(k > 0 ? responses[0].size() : 0, k);
  for (Eigen::Index j = 0; j < k; ++j) {
    axes.intrinsics_steps.col(j) = steps[static_cast<std::size_t>(j)];
    axes.responses.col(j) = responses[static_cast<std::size_t>(j)];
  }
  return axes;
}

Eigen::MatrixXd PropagateIntrinsicsCovariance(
    const CameraModel& camera, const std::function<Eigen::VectorXd(const CameraModel&)>& f) {
  const IntrinsicsAxes axes = PropagateIntrinsicsAxes(camera, f);
  return axes.responses * axes.responses.transpose();
}

}  // namespace lasercell::calib
