#include "calib/internal/kinematic_sphere_seed.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <random>

namespace lasercell::calib::internal {

std::optional<SeedSphere> AlgebraicSphere(const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<int>& indices) {
  if (indices.size() < 4) return std::nullopt;
  // Centre the data for conditioning.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : indices) mean += points[i];
  mean /= static_cast<double>(indices.size());
  Eigen::MatrixXd a(indices.size(), 4);
  Eigen::VectorXd b(indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    const Eigen::Vector3d p = points[indices[k]] - mean;
    a.row(static_cast<Eigen::Index>(k)) << 2 * p.x(), 2 * p.y(), 2 * p.z(), 1.0;
    b[static_cast<Eigen::Index>(k)] = p.squaredNorm();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  qr.setThreshold(1e-9);
  if (qr.rank() < 4) return std::nullopt;
  const Eigen::Vector4d x = qr.solve(b);
  const double r2 = x[3] + x.head<3>().squaredNorm();
  if (!(r2 > 0) || !std::isfinite(r2)) return std::nullopt;
  SeedSphere s;
  s.centre = x.head<3>() + mean;
  s.radius_mm = std::sqrt(r2);
  return s;
}

namespace {

constexpr std::size_t kMaxScoringPoints = 2500;

/// Standard deviation of the points across their best-fitting plane, mm.
double PlaneThickness(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& idx) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : idx) mean += points[i];
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : idx) cov += (points[i] - mean) * (points[i] - mean).transpose();
  cov /= static_cast<double>(idx.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  return std::sqrt(std::max(0.0, eig.eigenvalues()[0]));
}

}  // namespace

std::vector<SeedSphere> FindSpheres(const std::vector<Eigen::Vector3d>& points,
                                    const FindSphereOptions& options, int count) {
  std::vector<SeedSphere> found;
  std::vector<Eigen::Vector3d> rest = points;
  std::vector<int> original(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) original[i] = static_cast<int>(i);
  for (int k = 0; k < count; ++k) {
    FindSphereOptions o = options;
    o.seed = options.seed + 7919u * static_cast<unsigned>(k);
    std::optional<SeedSphere> s = FindSphere(rest, o);
    if (!s) break;
    std::vector<bool> taken(rest.size(), false);
    for (int i : s->inliers) taken[static_cast<std::size_t>(i)] = true;
    std::vector<Eigen::Vector3d> next;
    std::vector<int> next_original;
    for (int& i : s->inliers) i = original[static_cast<std::size_t>(i)];
    for (std::size_t i = 0; i < rest.size(); ++i) {
      if (!taken[i]) {
        next.push_back(rest[i]);
        next_original.push_back(original[i]);
      }
    }
    found.push_back(std::move(*s));
    rest = std::move(next);
    original = std::move(next_original);
  }
  return found;
}

std::optional<SeedSphere> FindSphere(const std::vector<Eigen::Vector3d>& points,
                                     const FindSphereOptions& options) {
  std::vector<int> candidates;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    if (!options.near_centre ||
        (points[i] - *options.near_centre).norm() <= options.near_distance_mm) {
      candidates.push_back(i);
    }
  }
  if (candidates.size() < 10) return std::nullopt;
  std::mt19937 rng(options.seed);
  auto draw = [&](std::size_t n) { return static_cast<std::size_t>(rng() % n); };
  // Hypotheses are drawn and scored on an even subset (speed); the winner is refined on all.
  std::vector<int> scoring;
  const std::size_t stride = (candidates.size() + kMaxScoringPoints - 1) / kMaxScoringPoints;
  for (std::size_t k = 0; k < candidates.size(); k += stride) scoring.push_back(candidates[k]);
  const auto inliers_among = [&](const SeedSphere& s, const std::vector<int>& among) {
    std::vector<int> in;
    for (int i : among) {
      if (std::abs((points[i] - s.centre).norm() - s.radius_mm) < options.inlier_gate_mm) {
        in.push_back(i);
      }
    }
    return in;
  };
  const auto inliers_of = [&](const SeedSphere& s) { return inliers_among(s, candidates); };
  std::optional<SeedSphere> best;
  std::vector<int> near;
  const double r2 = options.neighbourhood_mm * options.neighbourhood_mm;
  for (int h = 0; h < options.hypotheses; ++h) {
    const int seed = scoring[draw(scoring.size())];
    near.clear();
    for (int i : scoring) {
      if ((points[i] - points[seed]).squaredNorm() < r2) near.push_back(i);
    }
    if (near.size() < 4) continue;
    std::vector<int> sample = {seed};
    while (sample.size() < 4) sample.push_back(near[draw(near.size())]);
    std::optional<SeedSphere> s = AlgebraicSphere(points, sample);
    if (!s || s->radius_mm < options.min_radius_mm || s->radius_mm > options.max_radius_mm) {
      continue;
    }
    s->inliers = inliers_among(*s, scoring);
    if (best && s->inliers.size() <= best->inliers.size()) continue;
    if (s->inliers.size() < 10 * scoring.size() / candidates.size()) continue;
    if (s->inliers.size() < 4) continue;
    // A plane that fits the inliers about as well as the sphere: a patch of floor or deck.
    double sphere_ms = 0;
    for (int i : s->inliers) {
      const double d = (points[i] - s->centre).norm() - s->radius_mm;
      sphere_ms += d * d;
    }
    sphere_ms /= static_cast<double>(s->inliers.size());
    if (PlaneThickness(points, s->inliers) < 3 * std::sqrt(sphere_ms) + 1e-3) continue;
    best = std::move(s);
  }
  if (!best) return std::nullopt;
  best->inliers = inliers_of(*best);
  if (best->inliers.size() < 10) return std::nullopt;
  for (int round = 0; round < 2; ++round) {
    std::optional<SeedSphere> refined = AlgebraicSphere(points, best->inliers);
    if (!refined || refined->radius_mm < options.min_radius_mm ||
        refined->radius_mm > options.max_radius_mm) {
      break;
    }
    refined->inliers = inliers_of(*refined);
    if (refined->inliers.size() < 10) break;
    best = std::move(refined);
  }
  return best;
}

}  // namespace lasercell::calib::internal
