#include "core/se3.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace lasercell {

Eigen::Quaterniond QuaternionFromRotationVector(const Eigen::Vector3d& rotation_vector) {
  const double angle = rotation_vector.norm();
  const double half = 0.5 * angle;
  // sin(x/2)/x by its Taylor series near zero avoids 0/0.
  const double k = angle < 1e-8 ? 0.5 - angle * angle / 48.0 : std::sin(half) / angle;
  Eigen::Quaterniond q(std::cos(half), k * rotation_vector.x(), k * rotation_vector.y(),
                       k * rotation_vector.z());
  return q.normalized();
}

Eigen::Vector3d RotationVectorFromQuaternion(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // angle in [0, pi]
  const double sin_half = q.vec().norm();
  if (sin_half < 1e-12) return 2.0 * q.vec();  // first order
  const double angle = 2.0 * std::atan2(sin_half, q.w());
  return q.vec() * (angle / sin_half);
}

Eigen::Vector3d RotationVectorFromMatrix(const Eigen::Matrix3d& rotation) {
  return RotationVectorFromQuaternion(Eigen::Quaterniond(rotation));
}

Eigen::Isometry3d PoseFromRotationVector(const Eigen::Vector3d& rotation_vector,
                                         const Eigen::Vector3d& translation_mm) {
  return PoseFromQuaternion(QuaternionFromRotationVector(rotation_vector), translation_mm);
}

Eigen::Isometry3d PoseFromQuaternion(const Eigen::Quaterniond& q,
                                     const Eigen::Vector3d& translation_mm) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = translation_mm;
  return pose;
}

Vector6d RotationVectorTranslation(const Eigen::Isometry3d& pose) {
  Vector6d v;
  v.head<3>() = RotationVectorFromMatrix(pose.linear());
  v.tail<3>() = pose.translation();
  return v;
}

Eigen::Isometry3d PoseFromRotationVectorTranslation(const Vector6d& v) {
  return PoseFromRotationVector(v.head<3>(), v.tail<3>());
}

double RotationDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  // theta = 2 acos(|<qa, qb>|) (Skotheim et al. IV-E), written with atan2 for accuracy near 0.
  const Eigen::Quaterniond d = a.normalized().conjugate() * b.normalized();
  return 2.0 * std::atan2(d.vec().norm(), std::abs(d.w()));
}

double RotationDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return RotationDistance(Eigen::Quaterniond(a.linear()), Eigen::Quaterniond(b.linear()));
}

double TranslationDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

namespace {
std::vector<double> CheckedWeights(std::size_t n, std::span<const double> weights,
                                   const char* what) {
  if (n == 0) throw InputError(std::string(what) + ": nothing to average (empty input)");
  if (!weights.empty() && weights.size() != n) {
    throw InputError(std::string(what) + ": " + std::to_string(weights.size()) +
                     " weights for " + std::to_string(n) + " values");
  }
  std::vector<double> w(n, 1.0);
  double sum = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    if (!(weights[i] >= 0) || !std::isfinite(weights[i])) {
      throw InputError(std::string(what) + ": weight " + std::to_string(i) +
                       " is negative or not finite");
    }
    w[i] = weights[i];
  }
  for (double x : w) sum += x;
  if (!(sum > 0)) throw InputError(std::string(what) + ": weights sum to zero");
  for (double& x : w) x /= sum;
  return w;
}
}  // namespace

Eigen::Quaterniond AverageQuaternions(std::span<const Eigen::Quaterniond> quaternions,
                                      std::span<const double> weights) {
  const auto w = CheckedWeights(quaternions.size(), weights, "AverageQuaternions");
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  for (std::size_t i = 0; i < quaternions.size(); ++i) {
    const Eigen::Vector4d q = quaternions[i].normalized().coeffs();
    m += w[i] * q * q.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> solver(m);
  Eigen::Vector4d best = solver.eigenvectors().col(3);  // largest eigenvalue
  // Keep the sign of the first input so that averaging one quaternion returns it unchanged.
  if (best.dot(quaternions[0].coeffs()) < 0) best = -best;
  Eigen::Quaterniond q;
  q.coeffs() = best;
  return q.normalized();
}

Eigen::Isometry3d AveragePoses(std::span<const Eigen::Isometry3d> poses,
                               std::span<const double> weights) {
  const auto w = CheckedWeights(poses.size(), weights, "AveragePoses");
  std::vector<Eigen::Quaterniond> qs;
  qs.reserve(poses.size());
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < poses.size(); ++i) {
    qs.emplace_back(poses[i].linear());
    t += w[i] * poses[i].translation();
  }
  return PoseFromQuaternion(AverageQuaternions(qs, w), t);
}

Eigen::Isometry3d InterpolatePoses(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                   double t) {
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  return PoseFromQuaternion(qa.slerp(t, qb),
                            (1.0 - t) * a.translation() + t * b.translation());
}

Eigen::Isometry3d Orthonormalized(const Eigen::Isometry3d& pose) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(pose.linear(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  Eigen::Isometry3d out = pose;
  out.linear() = svd.matrixU() * d * svd.matrixV().transpose();
  return out;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace lasercell
