#include "calib/robot_positioning.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "calib/cost_functions/kinematic_sphere_cost.hpp"
#include "core/error.hpp"

namespace lasercell::calib {

namespace {

// Central-difference steps: small against any parameter's sigma, large against rounding of
// coordinates of ~1e3 mm.
constexpr double kAngleStep = 1e-7;   // rad (joint offsets, alpha, hand-eye rotation)
constexpr double kLengthStep = 1e-5;  // mm (a, d, hand-eye translation)

Eigen::Vector3d Mapped(const DhChain& robot, const Eigen::Isometry3d& flange_from_sensor,
                       const std::vector<double>& q, const Eigen::Vector3d& p) {
  return robot.BaseFromFlange(q) * (flange_from_sensor * p);
}

}  // namespace

Eigen::Matrix3d PointCovarianceInBase(const JointIdentificationResult& result,
                                      const std::vector<double>& joints_rad,
                                      const Eigen::Vector3d& point_in_sensor) {
  const int joints = static_cast<int>(result.robot.NumJoints());
  if (static_cast<int>(joints_rad.size()) != joints) {
    throw InputError("positioning uncertainty: " + std::to_string(joints_rad.size()) +
                     " joint values for a " + std::to_string(joints) + "-joint robot");
  }
  if (!point_in_sensor.allFinite() || std::any_of(joints_rad.begin(), joints_rad.end(),
                                                  [](double v) { return !std::isfinite(v); })) {
    throw InputError("positioning uncertainty: non-finite joint values or point");
  }
  const auto n = static_cast<Eigen::Index>(result.covariance_names.size());
  if (result.covariance.rows() != n || result.covariance.cols() != n) {
    throw InputError("positioning uncertainty: the result's covariance is " +
                     std::to_string(result.covariance.rows()) + "x" +
                     std::to_string(result.covariance.cols()) + " for " + std::to_string(n) +
                     " named parameters");
  }
  const std::vector<double> theta = DhParameterVector(result.robot);
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(3, n);
  for (Eigen::Index c = 0; c < n; ++c) {
    const std::string& name = result.covariance_names[static_cast<std::size_t>(c)];
    if (name.rfind("hand_eye_", 0) == 0) {
      const auto* found =
          std::find(kHandEyeParameterNames.begin(), kHandEyeParameterNames.end(), name);
      if (found == kHandEyeParameterNames.end()) {
        throw InputError("positioning uncertainty: unknown covariance parameter '" + name +
                         "' (hand_eye_rx .. hand_eye_tz)");
      }
      const auto axis = static_cast<int>(found - kHandEyeParameterNames.begin());
      const double h = axis < 3 ? kAngleStep : kLengthStep;
      double w_u[6] = {0, 0, 0, 0, 0, 0};
      Eigen::Vector3d side[2];
      for (int s = 0; s < 2; ++s) {
        w_u[axis] = s == 0 ? h : -h;
        Eigen::Matrix3d r;
        Eigen::Vector3d t;
        PerturbedFlangeFromSensor(result.flange_from_sensor, w_u, &r, &t);
        Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
        x.linear() = r;
        x.translation() = t;
        side[s] = Mapped(result.robot, x, joints_rad, point_in_sensor);
      }
      jac.col(c) = (side[0] - side[1]) / (2 * h);
      continue;
    }
    for (int k = 0; k < static_cast<int>(theta.size()); ++k) {
      if (DhParameterName(k, joints) != name) continue;
      const DhParameterKind kind = DhParameterKindAt(k, joints);
      const double h =
          kind == DhParameterKind::kA || kind == DhParameterKind::kD ? kLengthStep : kAngleStep;
      std::vector<double> plus = theta, minus = theta;
      plus[static_cast<std::size_t>(k)] += h;
      minus[static_cast<std::size_t>(k)] -= h;
      jac.col(c) = (Mapped(WithDhParameters(result.robot, plus), result.flange_from_sensor,
                           joints_rad, point_in_sensor) -
                    Mapped(WithDhParameters(result.robot, minus), result.flange_from_sensor,
                           joints_rad, point_in_sensor)) /
                   (2 * h);
    }
  }
  return jac * result.covariance * jac.transpose();
}

PositioningUncertainty PositioningAtSweeps(const JointIdentificationResult& result,
                                           const std::vector<SphereSweep>& sweeps) {
  PositioningUncertainty u;
  double sum2 = 0;
  for (const SphereSweep& w : sweeps) {
    if (w.profiles.empty()) continue;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    for (const SweptProfile& p : w.profiles) {
      for (const Eigen::Vector3d& x : p.points_in_sensor) centroid += x;
      count += p.points_in_sensor.size();
    }
    if (count == 0) continue;
    centroid /= static_cast<double>(count);
    const SweptProfile& middle = w.profiles[w.profiles.size() / 2];
    const double sigma = std::sqrt(
        std::max(0.0, PointCovarianceInBase(result, middle.joints_rad, centroid).trace()));
    sum2 += sigma * sigma;
    u.max_mm = std::max(u.max_mm, sigma);
    ++u.poses;
  }
  if (u.poses > 0) u.rms_mm = std::sqrt(sum2 / u.poses);
  return u;
}

}  // namespace lasercell::calib
