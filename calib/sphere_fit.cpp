#include "calib/sphere_fit.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "calib/cost_functions/sphere_distance_cost.hpp"
#include "core/error.hpp"
#include "core/stats.hpp"

namespace lasercell::calib {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// One Ceres pass over the points with mask[i] != 0; returns the summary.
ceres::Solver::Summary SolvePass(std::span<const Eigen::Vector3d> points,
                                 const std::vector<std::uint8_t>& use, bool robust,
                                 const SphereFitOptions& options, Eigen::Vector3d& center,
                                 double& radius) {
  ceres::Problem problem;
  double c[3] = {center.x(), center.y(), center.z()};
  double r = radius;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!use[i]) continue;
    problem.AddResidualBlock(SphereDistanceCost::Create(points[i]),
                             robust ? new ceres::CauchyLoss(options.robust_loss_scale_mm) : nullptr,
                             c, &r);
  }
  if (options.radius_mm) problem.SetParameterBlockConstant(&r);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  center = Eigen::Vector3d(c[0], c[1], c[2]);
  radius = r;
  return summary;
}

std::string Fmt(const char* format, double a, double b = 0, double c = 0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, format, a, b, c);
  return buf;
}

// Initialisation: Kasa. With the radius known, place the centre on the Kasa centre's line
// through the points' mean at the known radius from it (the Kasa radius is biased on caps).
// Throws InputError for coplanar points with a free radius.
void InitialSphere(std::span<const Eigen::Vector3d> points, const SphereFitOptions& options,
                   Eigen::Vector3d* center_out, double* radius_out) {
  const std::size_t n = points.size();
  const bool radius_fixed = options.radius_mm.has_value();
  Eigen::Vector3d center;
  double radius;
  const auto algebraic = AlgebraicSphere(points);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(n);
  if (algebraic) {
    center = algebraic->first;
    radius = algebraic->second;
  } else {
    if (!radius_fixed) {
      throw InputError("the " + std::to_string(n) +
                       " points lie on a plane: the radius of a free-radius sphere is undefined; "
                       "give the radius");
    }
    // Coplanar with a known radius: start from the plane's normal side (either is a solution).
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
    center = mean + *options.radius_mm * eig.eigenvectors().col(0);
    radius = *options.radius_mm;
  }
  if (radius_fixed) {
    radius = *options.radius_mm;
    Eigen::Vector3d dir = center - mean;
    if (dir.norm() < 1e-12) dir = Eigen::Vector3d::UnitZ();
    // Keep the Kasa centre when it is plausible; else move it to the known radius.
    if (std::abs(dir.norm() - radius) > 0.5 * radius) center = mean + radius * dir.normalized();
  }
  *center_out = center;
  *radius_out = radius;
}

// Half-angle (deg) of the cone about `axis` holding 95 % of the unit directions.
double CapHalfAngleDeg(const std::vector<Eigen::Vector3d>& dirs, const Eigen::Vector3d& axis) {
  std::vector<double> angles;
  angles.reserve(dirs.size());
  for (const auto& u : dirs) {
    angles.push_back(std::acos(std::clamp(u.dot(axis), -1.0, 1.0)) * kRadToDeg);
  }
  if (angles.empty()) return 0;
  const auto k = static_cast<std::ptrdiff_t>(0.95 * static_cast<double>(angles.size() - 1));
  std::nth_element(angles.begin(), angles.begin() + k, angles.end());
  return angles[static_cast<std::size_t>(k)];
}

}  // namespace

void SphereFitOptions::Check() const {
  if (radius_mm && !(std::isfinite(*radius_mm) && *radius_mm > 0)) {
    throw OptionError(
        "SphereFitOptions.radius_mm must be positive and finite (or unset for a "
        "free radius)");
  }
  if (!(robust_loss_scale_mm > 0) || !std::isfinite(robust_loss_scale_mm)) {
    throw OptionError("SphereFitOptions.robust_loss_scale_mm must be positive");
  }
  if (!(outlier_threshold_sigma > 0) || !std::isfinite(outlier_threshold_sigma)) {
    throw OptionError("SphereFitOptions.outlier_threshold_sigma must be positive");
  }
  if (!(min_outlier_threshold_mm >= 0) || !std::isfinite(min_outlier_threshold_mm)) {
    throw OptionError("SphereFitOptions.min_outlier_threshold_mm must be >= 0");
  }
  if (!(min_cap_half_angle_deg > 0 && min_cap_half_angle_deg <= 90)) {
    throw OptionError("SphereFitOptions.min_cap_half_angle_deg must be in (0, 90]");
  }
  if (max_iterations <= 0) throw OptionError("SphereFitOptions.max_iterations must be positive");
}

std::optional<std::pair<Eigen::Vector3d, double>> AlgebraicSphere(
    std::span<const Eigen::Vector3d> points) {
  if (points.size() < 4) return std::nullopt;
  // Centre and scale first so the linear system is well conditioned (Kasa 1976 fit:
  // |q|^2 = 2 c.q + k, k = R^2 - |c|^2, with q = (p - mean) / scale).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  double scale = 0;
  for (const auto& p : points) scale += (p - mean).squaredNorm();
  scale = std::sqrt(scale / static_cast<double>(points.size()));
  if (!(scale > 0)) return std::nullopt;
  Eigen::MatrixXd a(points.size(), 4);
  Eigen::VectorXd b(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d q = (points[i] - mean) / scale;
    a.row(static_cast<Eigen::Index>(i)) << 2 * q.x(), 2 * q.y(), 2 * q.z(), 1.0;
    b[static_cast<Eigen::Index>(i)] = q.squaredNorm();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& s = svd.singularValues();
  // Coplanar (or collinear) points leave the system rank deficient: no finite sphere.
  if (s[3] < 1e-9 * s[0]) return std::nullopt;
  const Eigen::Vector4d x = svd.solve(b);
  const Eigen::Vector3d c = x.head<3>();
  const double r2 = x[3] + c.squaredNorm();
  if (!(r2 > 0) || !std::isfinite(r2)) return std::nullopt;
  return std::make_pair(Eigen::Vector3d(mean + scale * c), scale * std::sqrt(r2));
}

SphereFitResult FitSphere(std::span<const Eigen::Vector3d> points,
                          const SphereFitOptions& options) {
  options.Check();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw InputError("FitSphere: point " + std::to_string(i) + " is not finite");
    }
  }
  SphereFitResult result;
  result.radius_fixed = options.radius_mm.has_value();
  const std::size_t num_params = result.radius_fixed ? 3 : 4;
  const std::size_t n = points.size();
  result.outlier.assign(n, 0);
  result.residuals_mm.assign(n, 0.0);
  if (n < num_params + 1) {
    throw InputError(std::to_string(n) + " points: a sphere fit needs at least " +
                     std::to_string(num_params + 1) +
                     (result.radius_fixed ? " with the radius known" : " with a free radius"));
  }

  // Initialisation: Kasa (InitialSphere).
  Eigen::Vector3d center;
  double radius;
  InitialSphere(points, options, &center, &radius);

  // Robust pass over all points.
  std::vector<std::uint8_t> use(n, 1);
  const ceres::Solver::Summary robust = SolvePass(points, use, true, options, center, radius);
  result.iterations = static_cast<int>(robust.iterations.size());
  bool converged = robust.termination_type == ceres::CONVERGENCE;

  // Outlier flags from the robust residuals (MAD scale).
  std::vector<double> abs_res(n);
  for (std::size_t i = 0; i < n; ++i) abs_res[i] = std::abs((points[i] - center).norm() - radius);
  const double robust_sigma = 1.4826 * Median(abs_res);
  const double threshold =
      std::max(options.outlier_threshold_sigma * robust_sigma, options.min_outlier_threshold_mm);
  std::size_t inliers = 0;
  for (std::size_t i = 0; i < n; ++i) {
    use[i] = abs_res[i] <= threshold ? 1 : 0;
    inliers += use[i];
  }
  if (inliers < num_params + 1) {
    result.failure = "only " + std::to_string(inliers) + " of " + std::to_string(n) +
                     " points agree with one sphere";
    return result;
  }

  // Final least-squares pass over the inliers: the estimate and its covariance.
  const ceres::Solver::Summary final_pass = SolvePass(points, use, false, options, center, radius);
  result.iterations += static_cast<int>(final_pass.iterations.size());
  converged = converged && final_pass.termination_type == ceres::CONVERGENCE;
  result.converged = converged;
  result.termination = ceres::TerminationTypeToString(final_pass.termination_type);
  result.center = center;
  result.radius_mm = radius;

  // Residuals, Jacobian (analytic: d r / d c = -u, d r / d R = -1) and cap geometry.
  Eigen::Matrix4d jtj = Eigen::Matrix4d::Zero();
  double ssr = 0;
  Eigen::Vector3d dir_sum = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> dirs;
  dirs.reserve(inliers);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = points[i] - center;
    const double dist = d.norm();
    result.residuals_mm[i] = dist - radius;
    result.outlier[i] = use[i] ? 0 : 1;
    if (!use[i] || dist <= 0) continue;
    const Eigen::Vector3d u = d / dist;
    Eigen::Vector4d j;
    j << -u, -1.0;
    jtj += j * j.transpose();
    ssr += result.residuals_mm[i] * result.residuals_mm[i];
    dir_sum += u;
    dirs.push_back(u);
  }
  result.num_inliers = inliers;
  result.num_outliers = n - inliers;
  result.rms_mm = std::sqrt(ssr / static_cast<double>(inliers));
  const double dof = static_cast<double>(inliers) - static_cast<double>(num_params);
  result.residual_sigma_mm = std::sqrt(ssr / dof);
  const double s2 = result.residual_sigma_mm * result.residual_sigma_mm;
  if (result.radius_fixed) {
    const Eigen::Matrix3d info = jtj.topLeftCorner<3, 3>();
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(info);
    if (!lu.isInvertible()) {
      result.failure = "the points do not fix the centre (singular information matrix)";
      return result;
    }
    result.covariance.topLeftCorner<3, 3>() = s2 * info.inverse();
  } else {
    const Eigen::FullPivLU<Eigen::Matrix4d> lu(jtj);
    if (!lu.isInvertible()) {
      result.failure = "the points do not fix centre and radius (singular information matrix)";
      return result;
    }
    result.covariance = s2 * jtj.inverse();
    result.radius_sigma_mm = std::sqrt(std::max(0.0, result.covariance(3, 3)));
  }
  result.covariance = 0.5 * (result.covariance + result.covariance.transpose()).eval();

  // Cap: mean direction and the 95 % cone about it.
  result.cap_axis =
      dir_sum.norm() > 1e-12 ? Eigen::Vector3d(dir_sum.normalized()) : Eigen::Vector3d::Zero();
  result.cap_half_angle_deg = CapHalfAngleDeg(dirs, result.cap_axis);
  if (!result.radius_fixed && result.cap_half_angle_deg < options.min_cap_half_angle_deg) {
    result.radius_determined = false;
    result.warnings.push_back(
        Fmt("cap half-angle %.1f deg < %.1f deg: the cap is too small to fix the radius "
            "(radius 1-sigma %.3g mm); give the radius (SphereFitOptions.radius_mm)",
            result.cap_half_angle_deg, options.min_cap_half_angle_deg, result.radius_sigma_mm));
  }
  if (!converged) {
    result.warnings.push_back("Ceres did not report convergence (" + result.termination + ")");
  }
  result.success = true;
  return result;
}

std::string SphereFitResult::Summary() const {
  if (!success) return "sphere fit failed: " + failure;
  const Eigen::Vector3d s = CenterCovariance().diagonal().cwiseMax(0.0).cwiseSqrt();
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "sphere centre (%.4f, %.4f, %.4f) mm +- (%.4f, %.4f, %.4f), radius %.4f mm%s, "
                "rms %.4f mm, %zu inliers, %zu outliers, cap %.1f deg%s",
                center.x(), center.y(), center.z(), s.x(), s.y(), s.z(), radius_mm,
                radius_fixed ? " (given)" : "", rms_mm, num_inliers, num_outliers,
                cap_half_angle_deg, radius_determined ? "" : " (radius not determined)");
  return buf;
}

}  // namespace lasercell::calib
