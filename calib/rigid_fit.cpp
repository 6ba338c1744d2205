#include "calib/rigid_fit.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/error.hpp"

namespace lasercell::calib {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

void CheckCovariances(const std::vector<Eigen::Matrix3d>& c, std::size_t n, const char* which,
                      const std::string& item) {
  if (c.empty()) return;
  if (c.size() != n) {
    throw InputError(std::string("FitRigidTransform: ") + std::to_string(c.size()) + " " + which +
                     " covariances for " + std::to_string(n) + " points");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::LLT<Eigen::Matrix3d> llt(c[i]);
    if (!c[i].allFinite() || llt.info() != Eigen::Success) {
      throw InputError(std::string("FitRigidTransform: the ") + which + " covariance of " + item +
                       " " + std::to_string(i) + " is not positive definite");
    }
  }
}

}  // namespace

void RigidFitOptions::Check() const {
  if (!(min_off_line_mm > 0) || !std::isfinite(min_off_line_mm)) {
    throw OptionError("RigidFitOptions.min_off_line_mm must be positive");
  }
  if (max_iterations <= 0) throw OptionError("RigidFitOptions.max_iterations must be positive");
}

double MaxDistanceFromLine(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 2) return 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d dir = eig.eigenvectors().col(2);
  double worst = 0;
  for (const auto& p : points) {
    const Eigen::Vector3d d = p - mean;
    worst = std::max(worst, (d - d.dot(dir) * dir).norm());
  }
  return worst;
}

RigidFitResult FitRigidTransform(const std::vector<Eigen::Vector3d>& src,
                                 const std::vector<Eigen::Vector3d>& dst,
                                 const std::vector<Eigen::Matrix3d>& src_cov,
                                 const std::vector<Eigen::Matrix3d>& dst_cov,
                                 const RigidFitOptions& options) {
  options.Check();
  const std::string& item = options.item_name;
  if (src.size() != dst.size()) {
    throw InputError("FitRigidTransform: " + std::to_string(src.size()) + " source and " +
                     std::to_string(dst.size()) + " target " + item + "s do not correspond");
  }
  const std::size_t n = src.size();
  if (n < 3) {
    throw InputError("rigid fit: " + std::to_string(n) + " " + item + (n == 1 ? "" : "s") +
                     ": a rigid transform needs at least 3 non-collinear " + item +
                     "s (with 2 the rotation about their line is unobservable)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!src[i].allFinite() || !dst[i].allFinite()) {
      throw InputError("rigid fit: " + item + " " + std::to_string(i) + " is not finite");
    }
  }
  CheckCovariances(src_cov, n, "source", item);
  CheckCovariances(dst_cov, n, "target", item);
  RigidFitResult result;
  result.off_line_mm = std::min(MaxDistanceFromLine(src), MaxDistanceFromLine(dst));
  if (result.off_line_mm < options.min_off_line_mm) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.3g mm < %.3g mm", result.off_line_mm,
                  options.min_off_line_mm);
    throw InputError("rigid fit: the " + std::to_string(n) + " " + item +
                     "s are collinear (farthest from their common line: " + buf +
                     "): the rotation about that line is unobservable; add a " + item +
                     " off the line");
  }

  auto combined = [&](std::size_t i, const Eigen::Matrix3d& r) {
    Eigen::Matrix3d s = dst_cov.empty() ? Eigen::Matrix3d::Identity() : dst_cov[i];
    s += src_cov.empty() ? Eigen::Matrix3d::Identity()
                         : Eigen::Matrix3d(r * src_cov[i] * r.transpose());
    return s;
  };

  // 1. Closed form with scalar weights.
  std::vector<double> w(n);
  for (std::size_t i = 0; i < n; ++i) w[i] = 3.0 / combined(i, Eigen::Matrix3d::Identity()).trace();
  Eigen::Isometry3d t = HornRigidTransform(src, dst, w);
  result.closed_form = t;

  // 2. Gauss-Newton on the Mahalanobis cost, left perturbation:
  //    e_i(xi) = d_i - Exp(xi) (T s_i) ~ e_i - [-[q_i]x, I] xi, q_i = T s_i.
  Matrix6d info = Matrix6d::Zero();
  for (int it = 0; it < options.max_iterations; ++it) {
    info.setZero();
    Vector6d g = Vector6d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d q = t * src[i];
      const Eigen::Vector3d e = dst[i] - q;
      Eigen::Matrix<double, 3, 6> j;  // d q / d xi
      j.leftCols<3>() = -Skew(q);
      j.rightCols<3>() = Eigen::Matrix3d::Identity();
      const Eigen::Matrix3d s_inv = combined(i, t.linear()).inverse();
      info += j.transpose() * s_inv * j;
      g += j.transpose() * s_inv * e;
    }
    const Vector6d dx = info.ldlt().solve(g);
    t = Orthonormalized(PoseFromRotationVectorTranslation(dx) * t);
    result.iterations = it + 1;
    if (dx.head<3>().norm() < 1e-13 && dx.tail<3>().norm() < 1e-10) {
      result.converged = true;
      break;
    }
  }
  result.target_from_source = t;

  // Residuals and covariance at the solution.
  info.setZero();
  double ss = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d q = t * src[i];
    const Eigen::Vector3d e = dst[i] - q;
    Eigen::Matrix<double, 3, 6> j;
    j.leftCols<3>() = -Skew(q);
    j.rightCols<3>() = Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d s_inv = combined(i, t.linear()).inverse();
    info += j.transpose() * s_inv * j;
    const double m2 = e.dot(s_inv * e);
    result.residuals_mm.push_back(e);
    result.residual_norms_mm.push_back(e.norm());
    result.mahalanobis.push_back(std::sqrt(m2));
    result.chi2 += m2;
    ss += e.squaredNorm();
  }
  result.rms_mm = std::sqrt(ss / static_cast<double>(n));
  result.dof = static_cast<int>(3 * n) - 6;
  result.covariance = info.inverse();
  if (options.scale_covariance_by_residuals && result.dof > 0) {
    result.covariance *= result.chi2 / result.dof;
  }
  result.covariance = 0.5 * (result.covariance + result.covariance.transpose()).eval();
  return result;
}

Eigen::Vector3d RigidFitResult::RotationSigmaDeg() const {
  return covariance.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt() * kRadToDeg;
}

Eigen::Vector3d RigidFitResult::TranslationSigmaMm() const {
  return covariance.diagonal().tail<3>().cwiseMax(0.0).cwiseSqrt();
}

std::string RigidFitResult::Summary() const {
  const Eigen::Vector3d r = RotationSigmaDeg(), s = TranslationSigmaMm();
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "rigid fit over %zu points: rms %.4f mm, chi2/dof %.3g/%d, 1-sigma rotation "
                "(%.4f, %.4f, %.4f) deg, translation (%.4f, %.4f, %.4f) mm%s",
                residual_norms_mm.size(), rms_mm, chi2, dof, r.x(), r.y(), r.z(), s.x(), s.y(),
                s.z(), converged ? "" : " (not converged)");
  return buf;
}

}  // namespace lasercell::calib
