#include "core/pose_covariance.hpp"

#include <cmath>
#include <numbers>

namespace lasercell {
namespace {

// Below this angle (rad) the coefficients of V and V^-1 use their Taylor series: the closed
// forms cancel catastrophically near 0, and the next series terms are below 1e-16 here.
constexpr double kSeriesAngle = 1e-2;

// V(w) = I + A [w]x + B [w]x^2 (the left Jacobian of SO(3)).
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& w) {
  const double a = w.norm();
  const double a2 = a * a;
  const double c1 = a < kSeriesAngle ? 0.5 - a2 / 24.0 + a2 * a2 / 720.0 : (1.0 - std::cos(a)) / a2;
  const double c2 =
      a < kSeriesAngle ? 1.0 / 6.0 - a2 / 120.0 + a2 * a2 / 5040.0 : (a - std::sin(a)) / (a2 * a);
  const Eigen::Matrix3d k = Skew(w);
  return Eigen::Matrix3d::Identity() + c1 * k + c2 * k * k;
}

// V(w)^-1 = I - 1/2 [w]x + C [w]x^2, C = (1 - (a/2) cot(a/2)) / a^2.
Eigen::Matrix3d InverseLeftJacobian(const Eigen::Vector3d& w) {
  const double a = w.norm();
  const double a2 = a * a;
  const double c = a < kSeriesAngle ? 1.0 / 12.0 + a2 / 720.0 + a2 * a2 / 30240.0
                                    : (1.0 - 0.5 * a * std::sin(a) / (1.0 - std::cos(a))) / a2;
  const Eigen::Matrix3d k = Skew(w);
  return Eigen::Matrix3d::Identity() - 0.5 * k + c * k * k;
}

double Sqrt0(double variance) { return variance < 0.0 ? 0.0 : std::sqrt(variance); }

}  // namespace

Eigen::Isometry3d ExpSe3(const Vector6d& xi) {
  const Eigen::Vector3d w = xi.head<3>();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = QuaternionFromRotationVector(w).toRotationMatrix();
  pose.translation() = LeftJacobian(w) * xi.tail<3>();
  return pose;
}

Vector6d LogSe3(const Eigen::Isometry3d& pose) {
  Vector6d xi;
  xi.head<3>() = RotationVectorFromMatrix(pose.linear());
  xi.tail<3>() = InverseLeftJacobian(xi.head<3>()) * pose.translation();
  return xi;
}

Matrix6d Adjoint(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d r = pose.linear();
  Matrix6d ad = Matrix6d::Zero();
  ad.topLeftCorner<3, 3>() = r;
  ad.bottomRightCorner<3, 3>() = r;
  ad.bottomLeftCorner<3, 3>() = Skew(pose.translation()) * r;
  return ad;
}

Matrix6d ComposeCovariance(const Eigen::Isometry3d& a, const Matrix6d& cov_a,
                           const Matrix6d& cov_b) {
  const Matrix6d ad = Adjoint(a);
  const Matrix6d cov = cov_a + ad * cov_b * ad.transpose();
  return 0.5 * (cov + cov.transpose());  // exactly symmetric despite round-off
}

Matrix6d InverseCovariance(const Eigen::Isometry3d& pose, const Matrix6d& cov) {
  const Matrix6d ad = Adjoint(pose.inverse());
  const Matrix6d out = ad * cov * ad.transpose();
  return 0.5 * (out + out.transpose());
}

Eigen::Matrix3d PointCovariance(const Eigen::Isometry3d& pose, const Matrix6d& cov,
                                const Eigen::Vector3d& p_in_child) {
  const Eigen::Vector3d q = pose * p_in_child;
  Eigen::Matrix<double, 3, 6> j;
  j << -Skew(q), Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d out = j * cov * j.transpose();
  return 0.5 * (out + out.transpose());
}

Vector6d PoseSigma(const Matrix6d& cov) {
  Vector6d sigma;
  for (int k = 0; k < 6; ++k) sigma(k) = Sqrt0(cov(k, k));
  return sigma;
}

Eigen::Vector3d RotationSigmaDeg(const Matrix6d& cov) {
  return PoseSigma(cov).head<3>() * (180.0 / std::numbers::pi);
}

Eigen::Vector3d TranslationSigmaMm(const Matrix6d& cov) { return PoseSigma(cov).tail<3>(); }

}  // namespace lasercell
