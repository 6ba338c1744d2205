#include "datasets/robots.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/se3.hpp"

namespace lasercell::datasets {

DhChain ApplyRobotErrors(const DhChain& nominal, const RobotErrors& errors) {
  DhChain chain = nominal;
  auto& joints = chain.mutable_joints();
  const auto check_size = [&](const std::vector<double>& v, const char* field) {
    if (!v.empty() && v.size() != joints.size()) {
      throw InputError(std::string("robot errors: ") + field + " has " + std::to_string(v.size()) +
                       " values, the robot has " + std::to_string(joints.size()) + " joints");
    }
  };
  check_size(errors.joint_offset_rad, "joint_offset_rad");
  check_size(errors.a_error_mm, "a_error_mm");
  check_size(errors.d_error_mm, "d_error_mm");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (!errors.joint_offset_rad.empty()) joints[i].joint_offset_rad += errors.joint_offset_rad[i];
    if (!errors.a_error_mm.empty()) joints[i].a_mm += errors.a_error_mm[i];
    if (!errors.d_error_mm.empty()) joints[i].d_mm += errors.d_error_mm[i];
  }
  return chain;
}

DhChain ApproximateNachiSc15f() {
  constexpr double kHalfPi = std::numbers::pi / 2;
  // Typical 6-axis industrial arm of this class (not Nachi's published table).
  std::vector<DhJoint> joints(6);
  joints[0].d_mm = 450.0;
  joints[0].a_mm = 150.0;
  joints[0].alpha_rad = -kHalfPi;
  joints[1].a_mm = 570.0;
  joints[1].theta_offset_rad = -kHalfPi;
  joints[2].a_mm = 150.0;
  joints[2].alpha_rad = -kHalfPi;
  joints[3].d_mm = 640.0;
  joints[3].alpha_rad = kHalfPi;
  joints[4].alpha_rad = -kHalfPi;
  joints[5].d_mm = 100.0;
  return DhChain(DhConvention::kStandard, std::move(joints));
}

std::optional<std::vector<double>> SolveIk(const KinematicModel& model,
                                           const Eigen::Isometry3d& target,
                                           const std::vector<double>& seed,
                                           const IkOptions& options) {
  const int n = model.NumJoints();
  if (static_cast<int>(seed.size()) != n) {
    throw InputError("SolveIk: seed has " + std::to_string(seed.size()) + " joints, model has " +
                     std::to_string(n));
  }
  // Error as [rotation vector of target * current^-1; translation difference].
  const auto error = [&](const std::vector<double>& q) {
    const Eigen::Isometry3d current = model.BaseFromFlange(q);
    Vector6d e;
    e.head<3>() = RotationVectorFromMatrix(target.linear() * current.linear().transpose());
    e.tail<3>() = target.translation() - current.translation();
    return e;
  };
  std::vector<double> q = seed;
  // Rotation errors are weighted by a length so both parts count alike (1 rad ~ 500 mm).
  constexpr double kRotWeight = 500.0;
  for (int iter = 0; iter < options.max_iterations; ++iter) {
    const Vector6d e = error(q);
    if (e.tail<3>().norm() < options.tolerance_mm && e.head<3>().norm() < options.tolerance_rad) {
      return q;
    }
    Eigen::Matrix<double, 6, Eigen::Dynamic> jac(6, n);
    const double h = 1e-7;
    for (int j = 0; j < n; ++j) {
      std::vector<double> qp = q, qm = q;
      qp[j] += h;
      qm[j] -= h;
      jac.col(j) = -(error(qp) - error(qm)) / (2 * h);  // d(current)/dq in error coordinates
    }
    Eigen::Matrix<double, 6, 1> w;
    w << kRotWeight, kRotWeight, kRotWeight, 1, 1, 1;
    const Eigen::MatrixXd jw = w.asDiagonal() * jac;
    const Eigen::VectorXd ew = w.asDiagonal() * e;
    const Eigen::MatrixXd lhs =
        jw.transpose() * jw + options.damping * Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd dq = lhs.ldlt().solve(jw.transpose() * ew);
    const double biggest = dq.cwiseAbs().maxCoeff();
    if (biggest > options.max_step_rad) dq *= options.max_step_rad / biggest;
    for (int j = 0; j < n; ++j) q[j] += dq[j];
  }
  const Vector6d e = error(q);
  if (e.tail<3>().norm() < 1e3 * options.tolerance_mm &&
      e.head<3>().norm() < 1e3 * options.tolerance_rad) {
    return q;
  }
  return std::nullopt;
}

}  // namespace lasercell::datasets
