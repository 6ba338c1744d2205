#include "calib/circle_fit.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>

#include "core/error.hpp"
#include "core/stats.hpp"

namespace lasercell::calib {
namespace {

struct Circle {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double radius = 0;
};

// The circle through three points (circumcircle), or nullopt when they are (nearly) collinear.
std::optional<Circle> ThroughThree(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                   const Eigen::Vector2d& c) {
  const Eigen::Vector2d ab = b - a, ac = c - a;
  const double cross = ab.x() * ac.y() - ab.y() * ac.x();
  const double scale = ab.squaredNorm() * ac.squaredNorm();
  if (!(cross * cross > 1e-12 * scale)) return std::nullopt;
  const double ab2 = ab.squaredNorm(), ac2 = ac.squaredNorm();
  const Eigen::Vector2d offset((ac.y() * ab2 - ab.y() * ac2) / (2 * cross),
                               (ab.x() * ac2 - ac.x() * ab2) / (2 * cross));
  return Circle{a + offset, offset.norm()};
}

double Residual(const Circle& c, const Eigen::Vector2d& p) {
  return (p - c.centre).norm() - c.radius;
}

// RANSAC: the three-point circle within the radius range with the most points within the gate.
std::optional<Circle> Consensus(std::span<const Eigen::Vector2d> points,
                                const CircleFitOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::optional<Circle> best;
  std::size_t best_support = 0;
  for (int it = 0; it < o.ransac_iterations; ++it) {
    const std::size_t i = pick(rng), j = pick(rng), k = pick(rng);
    if (i == j || j == k || i == k) continue;
    const std::optional<Circle> c = ThroughThree(points[i], points[j], points[k]);
    if (!c || c->radius < o.min_radius_mm || c->radius > o.max_radius_mm) continue;
    std::size_t support = 0;
    for (const Eigen::Vector2d& p : points) {
      if (std::abs(Residual(*c, p)) <= o.inlier_gate_mm) ++support;
    }
    if (support > best_support) {
      best_support = support;
      best = c;
    }
  }
  if (best_support < o.min_points) return std::nullopt;
  return best;
}

// Geometric least squares over the flagged points: Gauss-Newton with Levenberg damping on
// r_i = |p_i - c| - R, J_i = [-(p_i - c)^T / |p_i - c|, -1]. Returns J^T J at the solution.
Eigen::Matrix3d Refine(std::span<const Eigen::Vector2d> points,
                       const std::vector<std::uint8_t>& use, Circle* circle) {
  double lambda = 1e-6;
  Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
  const auto cost_of = [&](const Circle& c) {
    double s = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (use[i]) s += std::pow(Residual(c, points[i]), 2);
    }
    return s;
  };
  double cost = cost_of(*circle);
  for (int it = 0; it < 50; ++it) {
    jtj.setZero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!use[i]) continue;
      const Eigen::Vector2d d = points[i] - circle->centre;
      const double n = d.norm();
      if (!(n > 0)) continue;
      const Eigen::Vector3d j(-d.x() / n, -d.y() / n, -1.0);
      jtj.noalias() += j * j.transpose();
      jtr += j * (n - circle->radius);
    }
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Eigen::Matrix3d damped = jtj;
      damped.diagonal() *= 1.0 + lambda;
      const Eigen::Vector3d step = -damped.ldlt().solve(jtr);
      const Circle next{circle->centre + step.head<2>(), circle->radius + step[2]};
      const double next_cost = cost_of(next);
      if (next_cost <= cost) {
        improved = true;
        const double gain = cost - next_cost;
        *circle = next;
        cost = next_cost;
        lambda = std::max(lambda * 0.1, 1e-12);
        if (step.norm() < 1e-10 || gain <= 1e-15 * (1.0 + cost)) return jtj;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) return jtj;
  }
  return jtj;
}

// Angle the flagged points span about the centre: 360 deg minus the largest empty gap.
double ArcDeg(std::span<const Eigen::Vector2d> points, const std::vector<std::uint8_t>& use,
              const Eigen::Vector2d& centre) {
  std::vector<double> angles;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (use[i])
      angles.push_back(std::atan2(points[i].y() - centre.y(), points[i].x() - centre.x()));
  }
  if (angles.size() < 2) return 0;
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2 * std::numbers::pi - angles.back();
  for (std::size_t i = 1; i < angles.size(); ++i) gap = std::max(gap, angles[i] - angles[i - 1]);
  return (2 * std::numbers::pi - gap) * 180.0 / std::numbers::pi;
}

}  // namespace

void CircleFitOptions::Check() const {
  const auto fail = [](const std::string& field, const std::string& problem) {
    throw OptionError("CircleFitOptions." + field + " " + problem);
  };
  if (!(min_radius_mm > 0)) fail("min_radius_mm", "must be > 0");
  if (!(max_radius_mm > min_radius_mm)) fail("max_radius_mm", "must exceed min_radius_mm");
  if (!(inlier_gate_mm > 0)) fail("inlier_gate_mm", "must be > 0");
  if (!(trim_sigmas > 0)) fail("trim_sigmas", "must be > 0");
  if (!(min_trim_mm >= 0)) fail("min_trim_mm", "must be >= 0");
  if (ransac_iterations <= 0) fail("ransac_iterations", "must be > 0");
  if (min_points < 3) fail("min_points", "must be >= 3 (three points fix a circle)");
}

std::string CircleFitResult::Summary() const {
  if (!success) return "no circle: " + failure;
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "centre (%.4f, %.4f) mm, radius %.4f +- %.4f mm, rms %.4f mm, %zu inliers, %zu "
                "outliers, arc %.1f deg",
                centre.x(), centre.y(), radius_mm, std::sqrt(std::max(covariance(2, 2), 0.0)),
                rms_mm, inliers, outliers, arc_deg);
  return buf;
}

CircleFitResult FitCircle(std::span<const Eigen::Vector2d> points,
                          const CircleFitOptions& options) {
  options.Check();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw InputError("FitCircle: point " + std::to_string(i) + " is not finite");
    }
  }
  if (points.size() < options.min_points) {
    throw InputError("FitCircle: " + std::to_string(points.size()) + " points; need at least " +
                     std::to_string(options.min_points) + " (CircleFitOptions.min_points)");
  }
  CircleFitResult out;
  std::optional<Circle> found = Consensus(points, options);
  if (!found) {
    out.failure = "no circle of radius " + std::to_string(options.min_radius_mm) + ".." +
                  std::to_string(options.max_radius_mm) + " mm gathers " +
                  std::to_string(options.min_points) + " points within " +
                  std::to_string(options.inlier_gate_mm) + " mm";
    return out;
  }
  Circle circle = *found;
  std::vector<std::uint8_t> use(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    use[i] = std::abs(Residual(circle, points[i])) <= options.inlier_gate_mm;
  }
  Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
  for (int round = 0; round < 10; ++round) {
    jtj = Refine(points, use, &circle);
    std::vector<double> abs_res;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (use[i]) abs_res.push_back(std::abs(Residual(circle, points[i])));
    }
    const double gate =
        std::min(options.inlier_gate_mm,
                 std::max(options.trim_sigmas * 1.4826 * Median(abs_res), options.min_trim_mm));
    bool changed = false;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::uint8_t keep = std::abs(Residual(circle, points[i])) <= gate;
      changed = changed || keep != use[i];
      use[i] = keep;
    }
    if (!changed) break;
  }
  double ssr = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (use[i]) {
      ++out.inliers;
      ssr += std::pow(Residual(circle, points[i]), 2);
    }
  }
  out.outliers = points.size() - out.inliers;
  if (out.inliers < options.min_points) {
    out.failure = "only " + std::to_string(out.inliers) + " points stay on the circle after " +
                  "trimming (CircleFitOptions.min_points " + std::to_string(options.min_points) +
                  ")";
    return out;
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(jtj);
  if (!lu.isInvertible() || !(circle.radius > 0)) {
    out.failure = "the inliers do not fix a circle (singular normal equations)";
    return out;
  }
  const double variance = ssr / static_cast<double>(out.inliers - 3 > 0 ? out.inliers - 3 : 1);
  out.success = true;
  out.centre = circle.centre;
  out.radius_mm = circle.radius;
  out.covariance = variance * lu.inverse();
  out.rms_mm = std::sqrt(ssr / static_cast<double>(out.inliers));
  out.arc_deg = ArcDeg(points, use, circle.centre);
  out.inlier = std::move(use);
  return out;
}

}  // namespace lasercell::calib
