#include "calib/sphere_segmentation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>

#include "core/error.hpp"

namespace lasercell::calib {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// Integer cell of a point; keys pack three 21-bit signed cell indices.
std::uint64_t Key(std::int64_t x, std::int64_t y, std::int64_t z) {
  constexpr std::int64_t kOff = 1 << 20;
  constexpr std::uint64_t kMask = (1u << 21) - 1;
  return (static_cast<std::uint64_t>(x + kOff) & kMask) |
         ((static_cast<std::uint64_t>(y + kOff) & kMask) << 21) |
         ((static_cast<std::uint64_t>(z + kOff) & kMask) << 42);
}

// A spatial hash of point indices.
class Grid {
 public:
  Grid(const std::vector<Eigen::Vector3d>& points, double cell) : points_(points), cell_(cell) {
    for (std::size_t i = 0; i < points.size(); ++i) cells_[KeyOf(points[i])].push_back(i);
  }
  Grid(const std::vector<Eigen::Vector3d>& points, const std::vector<std::size_t>& subset,
       double cell)
      : points_(points), cell_(cell) {
    for (std::size_t i : subset) cells_[KeyOf(points[i])].push_back(i);
  }
  std::array<std::int64_t, 3> CellOf(const Eigen::Vector3d& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() / cell_)),
            static_cast<std::int64_t>(std::floor(p.y() / cell_)),
            static_cast<std::int64_t>(std::floor(p.z() / cell_))};
  }
  std::uint64_t KeyOf(const Eigen::Vector3d& p) const {
    const auto c = CellOf(p);
    return Key(c[0], c[1], c[2]);
  }
  // Calls f(index) for every stored point within r of q.
  template <typename F>
  void ForEachWithin(const Eigen::Vector3d& q, double r, F&& f) const {
    const auto c = CellOf(q);
    const auto k = static_cast<std::int64_t>(std::ceil(r / cell_));
    const double r2 = r * r;
    for (std::int64_t x = c[0] - k; x <= c[0] + k; ++x) {
      for (std::int64_t y = c[1] - k; y <= c[1] + k; ++y) {
        for (std::int64_t z = c[2] - k; z <= c[2] + k; ++z) {
          const auto it = cells_.find(Key(x, y, z));
          if (it == cells_.end()) continue;
          for (std::size_t i : it->second) {
            if ((points_[i] - q).squaredNorm() <= r2) f(i);
          }
        }
      }
    }
  }

 private:
  const std::vector<Eigen::Vector3d>& points_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells_;
};

// Small deterministic generator (splitmix64): identical on every platform.
struct SplitMix {
  std::uint64_t s;
  std::uint64_t Next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::size_t Below(std::size_t n) { return static_cast<std::size_t>(Next() % n); }
};

std::string Fmt(const char* format, double a, double b = 0) {
  char buf[200];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

// Largest connected component of `indices` (neighbours within `link`).
std::vector<std::size_t> LargestComponent(const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<std::size_t>& indices, double link) {
  const Grid grid(points, indices, link);
  std::unordered_map<std::size_t, int> label;
  label.reserve(indices.size());
  for (std::size_t i : indices) label[i] = -1;
  std::vector<std::size_t> best;
  int next = 0;
  for (std::size_t seed : indices) {
    if (label[seed] >= 0) continue;
    std::vector<std::size_t> comp;
    std::deque<std::size_t> queue{seed};
    label[seed] = next;
    while (!queue.empty()) {
      const std::size_t i = queue.front();
      queue.pop_front();
      comp.push_back(i);
      grid.ForEachWithin(points[i], link, [&](std::size_t j) {
        int& l = label[j];
        if (l < 0) {
          l = next;
          queue.push_back(j);
        }
      });
    }
    ++next;
    if (comp.size() > best.size()) best = std::move(comp);
  }
  std::sort(best.begin(), best.end());
  return best;
}

// Step 1. Voting samples: the first point of every sample_spacing voxel.
std::vector<std::size_t> VotingSamples(const std::vector<Eigen::Vector3d>& pts, double s) {
  std::vector<std::size_t> samples;
  std::unordered_map<std::uint64_t, std::size_t> voxel;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::uint64_t k = Key(static_cast<std::int64_t>(std::floor(pts[i].x() / s)),
                                static_cast<std::int64_t>(std::floor(pts[i].y() / s)),
                                static_cast<std::int64_t>(std::floor(pts[i].z() / s)));
    if (voxel.emplace(k, i).second) samples.push_back(i);
  }
  return samples;
}

// Step 2. PCA normals and centre votes (both signs), per vote_cell_mm cell key.
std::unordered_map<std::uint64_t, int> CentreVotes(const std::vector<Eigen::Vector3d>& pts,
                                                   const std::vector<std::size_t>& samples,
                                                   const SphereSegmentationOptions& options) {
  const Grid grid(pts, options.normal_radius_mm);
  std::unordered_map<std::uint64_t, int> votes;
  const double vc = options.vote_cell_mm;
  auto vote_cell = [&](const Eigen::Vector3d& c) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor(c.x() / vc)),
                                       static_cast<std::int64_t>(std::floor(c.y() / vc)),
                                       static_cast<std::int64_t>(std::floor(c.z() / vc))};
  };
  for (std::size_t i : samples) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    int count = 0;
    grid.ForEachWithin(pts[i], options.normal_radius_mm, [&](std::size_t j) {
      mean += pts[j];
      second += pts[j] * pts[j].transpose();
      ++count;
    });
    if (count < 6) continue;
    mean /= count;
    const Eigen::Matrix3d cov = second / count - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    // A line-like neighbourhood (one profile only) gives no normal.
    if (eig.eigenvalues()[1] < 1e-3 * eig.eigenvalues()[2]) continue;
    const Eigen::Vector3d n = eig.eigenvectors().col(0);
    for (double sign : {1.0, -1.0}) {
      const auto c = vote_cell(pts[i] + sign * options.radius_mm * n);
      ++votes[Key(c[0], c[1], c[2])];
    }
  }
  return votes;
}

struct Peak {
  std::array<std::int64_t, 3> cell;
  int sum;
};

// Step 3. Peaks of the 27-cell sums, strongest first.
std::vector<Peak> VotePeaks(const std::unordered_map<std::uint64_t, int>& votes, int min_votes) {
  std::vector<Peak> peaks;
  std::unordered_map<std::uint64_t, int> sums;
  std::unordered_map<std::uint64_t, std::array<std::int64_t, 3>> cells;
  for (const auto& [key, v] : votes) {
    (void)v;
    const std::int64_t kOff = 1 << 20;
    const std::array<std::int64_t, 3> c = {
        static_cast<std::int64_t>(key & ((1u << 21) - 1)) - kOff,
        static_cast<std::int64_t>((key >> 21) & ((1u << 21) - 1)) - kOff,
        static_cast<std::int64_t>((key >> 42) & ((1u << 21) - 1)) - kOff};
    int s = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = votes.find(Key(c[0] + dx, c[1] + dy, c[2] + dz));
          if (it != votes.end()) s += it->second;
        }
    sums[key] = s;
    cells[key] = c;
  }
  for (const auto& [key, s] : sums) {
    if (s < min_votes) continue;
    const auto& c = cells[key];
    bool is_max = true;
    for (int dx = -1; dx <= 1 && is_max; ++dx)
      for (int dy = -1; dy <= 1 && is_max; ++dy)
        for (int dz = -1; dz <= 1 && is_max; ++dz) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const std::uint64_t k2 = Key(c[0] + dx, c[1] + dy, c[2] + dz);
          const auto it = sums.find(k2);
          if (it == sums.end()) continue;
          // Ties go to the smaller key so exactly one cell of a plateau survives.
          if (it->second > s || (it->second == s && k2 < key)) is_max = false;
        }
    if (is_max) peaks.push_back({c, s});
  }
  std::sort(peaks.begin(), peaks.end(), [](const Peak& a, const Peak& b) {
    if (a.sum != b.sum) return a.sum > b.sum;
    return a.cell < b.cell;
  });
  return peaks;
}

// What the examination of one candidate (steps 4-5) needs.
struct CandidateContext {
  const PointCloud& cloud;
  const SphereSegmentationOptions& options;
  SphereFitOptions fit_options;  // radius fixed or free per options.fix_radius
  Eigen::Vector3d towards;       // unit, or zero: no facing check
  const Grid& search_grid;
};

// Step 4, RANSAC: the candidate itself (nominal radius) and 4-point algebraic spheres; returns
// the consensus of the best.
std::vector<std::size_t> RansacConsensus(const CandidateContext& ctx,
                                         const std::vector<std::size_t>& near,
                                         const Eigen::Vector3d& guess, std::uint64_t stream) {
  const std::vector<Eigen::Vector3d>& pts = ctx.cloud.positions;
  const SphereSegmentationOptions& options = ctx.options;
  const double r_nom = options.radius_mm;
  SplitMix rng{stream};
  std::size_t best_count = 0;
  Eigen::Vector3d best_c = guess;
  double best_r = r_nom;
  auto count_inliers = [&](const Eigen::Vector3d& c, double r) {
    std::size_t k = 0;
    for (std::size_t j : near) k += std::abs((pts[j] - c).norm() - r) < options.ransac_threshold_mm;
    return k;
  };
  best_count = count_inliers(guess, r_nom);
  for (int it = 0; it < options.ransac_iterations; ++it) {
    std::array<Eigen::Vector3d, 4> s;
    std::array<std::size_t, 4> pick{};
    for (int k = 0; k < 4; ++k) {
      pick[static_cast<std::size_t>(k)] = near[rng.Below(near.size())];
      s[static_cast<std::size_t>(k)] = pts[pick[static_cast<std::size_t>(k)]];
    }
    const auto sphere = AlgebraicSphere(s);
    if (!sphere || std::abs(sphere->second - r_nom) > options.radius_tolerance_mm) continue;
    if ((sphere->first - guess).norm() > r_nom) continue;
    const double r = options.fix_radius ? r_nom : sphere->second;
    const std::size_t k = count_inliers(sphere->first, r);
    if (k > best_count) {
      best_count = k;
      best_c = sphere->first;
      best_r = r;
    }
  }
  std::vector<std::size_t> consensus;
  for (std::size_t j : near) {
    if (std::abs((pts[j] - best_c).norm() - best_r) < options.ransac_threshold_mm) {
      consensus.push_back(j);
    }
  }
  return consensus;
}

// Step 5, the shape tests of a fitted candidate with inlier distance `thr`: empty when it is a
// sphere seen from the sensor, else the reason it is not. Sets *shell_fraction.
std::string ShapeRejection(const CandidateContext& ctx, const SphereFitResult& fit, double thr,
                           const std::vector<std::size_t>& near, double* shell_fraction) {
  const std::vector<Eigen::Vector3d>& pts = ctx.cloud.positions;
  const SphereSegmentationOptions& options = ctx.options;
  const double r_nom = options.radius_mm;
  if (!options.fix_radius && std::abs(fit.radius_mm - r_nom) > options.radius_tolerance_mm) {
    return Fmt("fitted radius %.3f mm is not the nominal %.3f mm", fit.radius_mm, r_nom);
  }
  if (fit.cap_half_angle_deg < options.min_cap_half_angle_deg) {
    return Fmt("cap half-angle %.1f deg < %.1f deg (not a sphere cap)", fit.cap_half_angle_deg,
               options.min_cap_half_angle_deg);
  }
  if (fit.rms_mm > options.max_rms_fraction * thr) {
    return Fmt(
        "residuals fill the +-%.3f mm band evenly (rms %.3f mm): a surface "
        "crossing a sphere, not a sphere",
        thr, fit.rms_mm);
  }
  // Shell test inside the cap's cone: inliers / points within 3 inlier distances.
  const double cos_cap = std::cos(fit.cap_half_angle_deg / kRadToDeg);
  std::size_t shell = 0, on_sphere = 0;
  for (std::size_t j : near) {
    const Eigen::Vector3d d = pts[j] - fit.center;
    const double dist = d.norm();
    const double res = std::abs(dist - fit.radius_mm);
    if (res > 3 * thr || d.dot(fit.cap_axis) < cos_cap * dist) continue;
    ++shell;
    on_sphere += res < thr;
  }
  const double fraction = shell > 0 ? static_cast<double>(on_sphere) / shell : 0.0;
  *shell_fraction = fraction;
  if (fraction < options.min_shell_fraction) {
    return Fmt(
        "only %.0f %% of the points near its shell lie on it (< %.0f %%): "
        "a surface crossing a sphere, not a sphere",
        100 * fraction, 100 * options.min_shell_fraction);
  }
  if (ctx.towards.norm() > 0) {
    const double tilt = std::acos(std::clamp(fit.cap_axis.dot(ctx.towards), -1.0, 1.0)) * kRadToDeg;
    if (tilt > options.max_cap_tilt_deg) {
      return Fmt(
          "cap axis %.1f deg from the sensor direction (> %.1f deg): a "
          "stand, a ring or a concave patch, not a sphere seen from the "
          "sensor",
          tilt, options.max_cap_tilt_deg);
    }
  }
  return "";
}

// FitSphere on a candidate's points; points that cannot determine a sphere (InputError, e.g.
// all on a plane with a free radius) make a failed fit, i.e. a rejected candidate.
SphereFitResult FitCandidate(const std::vector<Eigen::Vector3d>& points,
                             const SphereFitOptions& options) {
  try {
    return FitSphere(points, options);
  } catch (const InputError& e) {
    SphereFitResult failed;
    failed.failure = e.what();
    return failed;
  }
}

// Steps 4-5 for one candidate at `guess` (points already taken by spheres skipped): the sphere,
// or nothing with *reason set. `stream` seeds the RANSAC draws.
std::optional<SegmentedSphere> ExamineCandidate(const CandidateContext& ctx,
                                                const Eigen::Vector3d& guess, int votes,
                                                const std::vector<std::uint8_t>& used,
                                                std::uint64_t stream, std::string* reason) {
  const std::vector<Eigen::Vector3d>& pts = ctx.cloud.positions;
  const SphereSegmentationOptions& options = ctx.options;
  std::vector<std::size_t> near;
  ctx.search_grid.ForEachWithin(
      guess, options.radius_mm + options.search_margin_mm + options.radius_tolerance_mm,
      [&](std::size_t j) {
        if (!used[j]) near.push_back(j);
      });
  std::sort(near.begin(), near.end());
  if (near.size() < options.min_points) {
    *reason = "only " + std::to_string(near.size()) + " points near the candidate";
    return std::nullopt;
  }
  const std::vector<std::size_t> consensus = RansacConsensus(ctx, near, guess, stream);
  if (consensus.size() < options.min_points) {
    *reason = "RANSAC consensus of " + std::to_string(consensus.size()) + " points < " +
              std::to_string(options.min_points);
    return std::nullopt;
  }
  // Refine, region-grow the inliers, refit.
  std::vector<Eigen::Vector3d> cp;
  for (std::size_t j : consensus) cp.push_back(pts[j]);
  SphereFitResult fit = FitCandidate(cp, ctx.fit_options);
  if (!fit.success) {
    *reason = "fit failed: " + fit.failure;
    return std::nullopt;
  }
  std::vector<std::size_t> inliers;
  const double thr =
      std::min(options.ransac_threshold_mm, std::max(4.0 * fit.residual_sigma_mm, 0.02));
  for (std::size_t j : near) {
    if (std::abs((pts[j] - fit.center).norm() - fit.radius_mm) < thr) inliers.push_back(j);
  }
  const std::vector<std::size_t> component =
      LargestComponent(pts, inliers, options.connectivity_mm);
  if (component.size() < options.min_points) {
    *reason = "largest connected surface patch has " + std::to_string(component.size()) +
              " points < " + std::to_string(options.min_points);
    return std::nullopt;
  }
  cp.clear();
  for (std::size_t j : component) cp.push_back(pts[j]);
  fit = FitCandidate(cp, ctx.fit_options);
  if (!fit.success) {
    *reason = "fit failed: " + fit.failure;
    return std::nullopt;
  }
  double shell_fraction = 0;
  *reason = ShapeRejection(ctx, fit, thr, near, &shell_fraction);
  if (!reason->empty()) return std::nullopt;
  // Step 6: noise correlated along the laser line inflates the covariance.
  const double kappa = LineCorrelationFactor(ctx.cloud, component, fit.residuals_mm, fit.outlier);
  if (kappa > 1.0) {
    fit.covariance *= kappa;
    fit.radius_sigma_mm *= std::sqrt(kappa);
    if (kappa > 1.5) {
      fit.warnings.push_back(
          Fmt("residuals are correlated along the laser line (speckle?): "
              "covariance inflated %.2fx",
              kappa));
    }
  }
  return SegmentedSphere{std::move(fit), component, votes, shell_fraction, thr, kappa};
}

}  // namespace

void SphereSegmentationOptions::Check() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) {
      throw OptionError(std::string("SphereSegmentationOptions.") + name + " must be positive");
    }
  };
  positive(radius_mm, "radius_mm");
  positive(radius_tolerance_mm, "radius_tolerance_mm");
  positive(sample_spacing_mm, "sample_spacing_mm");
  positive(normal_radius_mm, "normal_radius_mm");
  positive(vote_cell_mm, "vote_cell_mm");
  positive(ransac_threshold_mm, "ransac_threshold_mm");
  positive(connectivity_mm, "connectivity_mm");
  if (!(search_margin_mm >= 0)) {
    throw OptionError("SphereSegmentationOptions.search_margin_mm must be >= 0");
  }
  if (min_votes <= 0) throw OptionError("SphereSegmentationOptions.min_votes must be positive");
  if (max_candidates <= 0) {
    throw OptionError("SphereSegmentationOptions.max_candidates must be positive");
  }
  if (ransac_iterations <= 0) {
    throw OptionError("SphereSegmentationOptions.ransac_iterations must be positive");
  }
  if (min_points < 5) throw OptionError("SphereSegmentationOptions.min_points must be >= 5");
  if (!(min_cap_half_angle_deg > 0 && min_cap_half_angle_deg <= 90)) {
    throw OptionError("SphereSegmentationOptions.min_cap_half_angle_deg must be in (0, 90]");
  }
  if (!(min_shell_fraction > 0 && min_shell_fraction <= 1)) {
    throw OptionError("SphereSegmentationOptions.min_shell_fraction must be in (0, 1]");
  }
  if (!(max_rms_fraction > 0 && max_rms_fraction <= 1)) {
    throw OptionError("SphereSegmentationOptions.max_rms_fraction must be in (0, 1]");
  }
  if (!(max_cap_tilt_deg > 0 && max_cap_tilt_deg <= 180)) {
    throw OptionError("SphereSegmentationOptions.max_cap_tilt_deg must be in (0, 180]");
  }
  if (!towards_sensor.allFinite()) {
    throw OptionError("SphereSegmentationOptions.towards_sensor must be finite");
  }
  SphereFitOptions f = fit;
  f.radius_mm.reset();
  f.Check();
}

SphereSegmentationResult SegmentSpheres(const PointCloud& cloud,
                                        const SphereSegmentationOptions& options) {
  options.Check();
  SphereSegmentationResult result;
  const std::vector<Eigen::Vector3d>& pts = cloud.positions;
  if (pts.empty()) return result;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    // Cell indices must fit the hash keys; 1e8 mm (100 km) is far beyond any cell.
    if (!pts[i].allFinite() || pts[i].cwiseAbs().maxCoeff() > 1e8) {
      throw InputError("SegmentSpheres: point " + std::to_string(i) +
                       " is not finite or lies beyond 1e8 mm; the cloud must be in millimetres");
    }
  }
  const double r_nom = options.radius_mm;

  // 1.-3. Voting samples, centre votes, their peaks.
  const std::vector<std::size_t> samples = VotingSamples(pts, options.sample_spacing_mm);
  result.samples = samples.size();
  const std::vector<Peak> peaks = VotePeaks(CentreVotes(pts, samples, options), options.min_votes);

  // 4./5. Verify candidates, strongest first.
  std::vector<std::uint8_t> used(pts.size(), 0);
  std::vector<Eigen::Vector3d> kept_centers;
  const Grid search_grid(pts, std::max(options.normal_radius_mm, 0.25 * r_nom));
  CandidateContext ctx{cloud, options, options.fit,
                       options.towards_sensor.norm() > 0
                           ? Eigen::Vector3d(options.towards_sensor.normalized())
                           : Eigen::Vector3d::Zero(),
                       search_grid};
  if (options.fix_radius) {
    ctx.fit_options.radius_mm = r_nom;
  } else {
    ctx.fit_options.radius_mm.reset();
  }
  for (const Peak& peak : peaks) {
    if (static_cast<int>(result.candidates) >= options.max_candidates) break;
    if (result.spheres.size() >= options.max_spheres) break;
    const Eigen::Vector3d guess = (Eigen::Vector3d(peak.cell[0], peak.cell[1], peak.cell[2]) +
                                   Eigen::Vector3d::Constant(0.5)) *
                                  options.vote_cell_mm;
    bool near_kept = false;
    for (const auto& c : kept_centers) near_kept = near_kept || (c - guess).norm() < r_nom;
    if (near_kept) continue;
    ++result.candidates;
    std::string reason;
    std::optional<SegmentedSphere> sphere = ExamineCandidate(
        ctx, guess, peak.sum, used, options.seed * 0x1000193ull + result.candidates, &reason);
    if (!sphere) {
      result.rejected.push_back({guess, peak.sum, reason});
      continue;
    }
    for (std::size_t j : sphere->indices) used[j] = 1;
    kept_centers.push_back(sphere->fit.center);
    result.spheres.push_back(std::move(*sphere));
  }
  return result;
}

double LineCorrelationFactor(const PointCloud& cloud, const std::vector<std::size_t>& indices,
                             const std::vector<double>& residuals,
                             const std::vector<std::uint8_t>& outlier, int max_lag) {
  if (!cloud.HasProfile() || !cloud.HasColumn() || indices.size() < 10) return 1.0;
  // Residual per (profile, column), inliers only.
  std::unordered_map<std::uint64_t, double> at;
  double sum2 = 0;
  std::size_t n = 0;
  auto key = [](std::int64_t profile, std::int64_t column) {
    return (static_cast<std::uint64_t>(profile) << 32) ^ static_cast<std::uint64_t>(column);
  };
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (outlier[i]) continue;
    const std::size_t p = indices[i];
    at[key(cloud.profile[p], cloud.column[p])] = residuals[i];
    sum2 += residuals[i] * residuals[i];
    ++n;
  }
  if (n < 10 || !(sum2 > 0)) return 1.0;
  const double var = sum2 / static_cast<double>(n);
  double kappa = 1.0;
  for (int lag = 1; lag <= max_lag; ++lag) {
    double cross = 0;
    std::size_t pairs = 0;
    for (std::size_t i = 0; i < indices.size(); ++i) {
      if (outlier[i]) continue;
      const std::size_t p = indices[i];
      const auto it = at.find(key(cloud.profile[p], cloud.column[p] + lag));
      if (it == at.end()) continue;
      cross += residuals[i] * it->second;
      ++pairs;
    }
    if (pairs < 10) break;
    const double rho = cross / static_cast<double>(pairs) / var;
    if (rho <= 0) break;
    kappa += 2 * rho;
  }
  return kappa;
}

std::string SphereSegmentationResult::Summary() const {
  std::string s = std::to_string(spheres.size()) + " sphere" + (spheres.size() == 1 ? "" : "s");
  if (!spheres.empty()) {
    s += " (";
    for (std::size_t i = 0; i < spheres.size(); ++i) {
      s += (i ? ", " : "") + std::to_string(spheres[i].indices.size());
    }
    s += " points)";
  }
  s += ", " + std::to_string(rejected.size()) + " of " + std::to_string(candidates) +
       " candidates rejected, " + std::to_string(samples) + " voting samples";
  return s;
}

}  // namespace lasercell::calib
