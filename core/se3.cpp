#include "core/se3.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <array>
#include <charconv>
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
    throw InputError(std::string(what) + ": " + std::to_string(weights.size()) + " weights for " +
                     std::to_string(n) + " values");
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
  return PoseFromQuaternion(qa.slerp(t, qb), (1.0 - t) * a.translation() + t * b.translation());
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

Eigen::Quaterniond CanonicalQuaternion(const Eigen::Matrix3d& rotation) {
  Eigen::Quaterniond q = Eigen::Quaterniond(rotation).normalized();
  // The first nonzero of (w, x, y, z) positive; Eigen stores the coefficients as (x, y, z, w).
  for (const int i : {3, 0, 1, 2}) {
    if (q.coeffs()[i] == 0) continue;
    if (q.coeffs()[i] < 0) q.coeffs() = -q.coeffs();
    break;
  }
  for (int i = 0; i < 4; ++i) {
    if (q.coeffs()[i] == 0) q.coeffs()[i] = 0.0;  // +0, never -0
  }
  return q;
}

Eigen::Isometry3d QuaternionPose::ToIsometry() const {
  return PoseFromQuaternion(rotation, translation_mm);
}

QuaternionPose QuaternionPose::FromIsometry(const Eigen::Isometry3d& pose) {
  return {CanonicalQuaternion(pose.linear()), pose.translation()};
}

namespace {
/// Shortest text that reads back to the same double (as the cell-file writer prints numbers).
std::string Shortest(double value) {
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}
}  // namespace

void CheckRigidTransform(const Eigen::Isometry3d& pose, const std::string& what) {
  if (!pose.matrix().topRows<3>().allFinite()) {
    throw InputError(what + " has non-finite entries; pass a finite rigid transform");
  }
  const Eigen::Matrix3d r = pose.linear();
  const double orthonormality = (r.transpose() * r - Eigen::Matrix3d::Identity()).norm();
  if (!(orthonormality < 1e-9) || !(r.determinant() > 0)) {
    throw InputError(what + " has a rotation that is not orthonormal (|R^T R - I| = " +
                     Shortest(orthonormality) + ", det = " + Shortest(r.determinant()) +
                     "); pass a proper rotation (see Orthonormalized in core/se3.hpp)");
  }
}

void CheckQuaternionPose(const QuaternionPose& pose, const std::string& what) {
  if (!pose.rotation.coeffs().allFinite() || !pose.translation_mm.allFinite()) {
    throw InputError(what + " has non-finite entries; pass a finite rigid transform");
  }
  const double norm = pose.rotation.norm();
  if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance)) {
    throw InputError(what + ": rotation has norm " + Shortest(norm) +
                     "; pass a unit quaternion (norm within 1e-9 of 1), or set the pose from a "
                     "rotation matrix instead");
  }
}

Eigen::Matrix3d HornRotation(const Eigen::Matrix3d& cross_covariance,
                             Eigen::Vector3d* singular_values) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross_covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) s(2, 2) = -1.0;
  if (singular_values != nullptr) *singular_values = svd.singularValues();
  return svd.matrixU() * s * svd.matrixV().transpose();
}

Eigen::Isometry3d HornRigidTransform(const std::vector<Eigen::Vector3d>& src,
                                     const std::vector<Eigen::Vector3d>& dst,
                                     const std::vector<double>& weights) {
  // Umeyama 1991 without scale: weighted centroids, then the rotation of the cross-covariance.
  const std::size_t n = src.size();
  if (dst.size() != n || (!weights.empty() && weights.size() != n)) {
    throw InputError("rigid fit (closed form): " + std::to_string(n) + " source points, " +
                     std::to_string(dst.size()) + " target points and " +
                     std::to_string(weights.size()) + " weights do not correspond");
  }
  if (n < 3) {
    throw InputError("rigid fit (closed form): " + std::to_string(n) +
                     " points: a rigid transform needs at least 3 non-collinear points");
  }
  double wsum = 0;
  Eigen::Vector3d ms = Eigen::Vector3d::Zero(), md = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    ms += w * src[i];
    md += w * dst[i];
    wsum += w;
  }
  ms /= wsum;
  md /= wsum;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    h += w * (dst[i] - md) * (src[i] - ms).transpose();
  }
  if (!(wsum > 0) || !std::isfinite(wsum)) {
    throw InputError("rigid fit (closed form): the weights must be positive (their sum is " +
                     std::to_string(wsum) + ")");
  }
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = HornRotation(h);
  t.translation() = md - t.linear() * ms;
  return t;
}

Eigen::Matrix3d RotationFromFixedXyzDeg(const Eigen::Vector3d& xyz_deg) {
  const Eigen::Vector3d r = xyz_deg * (EIGEN_PI / 180.0);
  return (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d FixedXyzDegFromRotation(const Eigen::Matrix3d& rotation) {
  // R = Rz(c) Ry(b) Rx(a): R(2,0) = -sin b, R(0,0) = cos b cos c, R(1,0) = cos b sin c,
  // R(2,1) = cos b sin a, R(2,2) = cos b cos a. atan2 keeps b exact near +-90 degrees.
  const double cb = std::hypot(rotation(0, 0), rotation(1, 0));
  const double b = std::atan2(-rotation(2, 0), cb);
  double a = 0.0, c;
  if (cb < 1e-12) {
    c = std::atan2(-rotation(0, 1), rotation(1, 1));  // gimbal lock: a = 0 carries none
  } else {
    a = std::atan2(rotation(2, 1), rotation(2, 2));
    c = std::atan2(rotation(1, 0), rotation(0, 0));
  }
  return Eigen::Vector3d(a, b, c) * (180.0 / EIGEN_PI);
}

}  // namespace lasercell
