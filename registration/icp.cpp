#include "registration/icp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/pose_covariance.hpp"
#include "core/se3.hpp"

namespace lasercell::registration {
namespace {

constexpr std::size_t kChunk = 256;  // fixed chunking: sums do not depend on the thread count

// One source point's correspondence at the current pose.
struct Match {
  std::uint32_t target = 0;
  double residual = 0.0;  // signed point-to-plane distance or point distance, mm
  bool valid = false;
};

double Weight(RobustKernel kernel, double r, double sigma) {
  const double a = std::abs(r);
  switch (kernel) {
    case RobustKernel::kNone:
      return 1.0;
    case RobustKernel::kHuber:
      return a <= 1.345 * sigma ? 1.0 : 1.345 * sigma / a;
    case RobustKernel::kTukey: {
      const double c = 4.685 * sigma;
      if (a >= c) return 0.0;
      const double u = 1.0 - (r / c) * (r / c);
      return u * u;
    }
    case RobustKernel::kGemanMcClure: {
      const double s2 = sigma * sigma;
      const double u = s2 / (s2 + r * r);
      return u * u;
    }
  }
  return 1.0;
}

// Sums over one chunk of correspondences (both metrics' statistics; only one is used).
struct Partial {
  Matrix6d h = Matrix6d::Zero();  // point-to-plane normal equations
  Vector6d b = Vector6d::Zero();
  double w = 0.0;  // point-to-point weighted moments about the centroid c
  Eigen::Vector3d sum_a = Eigen::Vector3d::Zero(), sum_b = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
};

// What AlignIcp's stages share: the inputs, and per source point its position at the current
// pose and its correspondence (buffers reused by every association).
struct IcpProblem {
  std::span<const Eigen::Vector3d> source;
  const KdTree& target;
  std::span<const Eigen::Vector3d> target_normals;
  const IcpOptions& options;
  bool plane = true;    // point-to-plane (Chen & Medioni), else point-to-point
  double max_sq = 0.0;  // squared max correspondence distance, mm^2
  std::vector<Match> matches;
  std::vector<Eigen::Vector3d> moved;
  std::span<const Eigen::Vector3d> source_normals;  // empty: no normal compatibility test
  double min_normal_cos = -1.0;                     // |cos| below this: not a correspondence
};

// Nearest target point and residual for every source point at the current pose; returns the
// |residual| of the valid matches.
std::vector<double> Associate(IcpProblem& p, const Eigen::Isometry3d& pose) {
  const std::size_t n = p.source.size();
  const auto& target_points = p.target.points();
  ParallelForChunks(p.options.threads, n, kChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      p.moved[i] = pose * p.source[i];
      Neighbor nn;
      Match& m = p.matches[i];
      m.valid = p.target.Nearest(p.moved[i], &nn) && nn.distance_sq <= p.max_sq;
      if (m.valid && !p.source_normals.empty()) {
        const double cos = p.target_normals[nn.index].dot(pose.linear() * p.source_normals[i]);
        m.valid = std::abs(cos) >= p.min_normal_cos;
      }
      if (!m.valid) continue;
      m.target = nn.index;
      m.residual = p.plane ? p.target_normals[nn.index].dot(p.moved[i] - target_points[nn.index])
                           : std::sqrt(nn.distance_sq);
    }
  });
  std::vector<double> abs_r;
  abs_r.reserve(n);
  for (const Match& m : p.matches) {
    if (m.valid) abs_r.push_back(std::abs(m.residual));
  }
  return abs_r;
}

// Kernel scale: fixed, or 1.4826 x MAD (median of |r|, residuals being centred at 0).
double KernelScale(const IcpOptions& options, std::vector<double>& abs_r) {
  if (options.kernel_scale_mm > 0.0) return options.kernel_scale_mm;
  if (abs_r.empty()) return options.min_kernel_scale_mm;
  auto mid = abs_r.begin() + static_cast<std::ptrdiff_t>(abs_r.size() / 2);
  std::nth_element(abs_r.begin(), mid, abs_r.end());
  return std::max(options.min_kernel_scale_mm, 1.4826 * *mid);
}

// Centroid of the matched moved source points: the linearization point (conditioning far from
// the origin).
Eigen::Vector3d MatchedCentroid(const IcpProblem& p) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  std::size_t valid = 0;
  for (std::size_t i = 0; i < p.source.size(); ++i) {
    if (p.matches[i].valid) {
      c += p.moved[i];
      ++valid;
    }
  }
  c /= static_cast<double>(valid);
  return c;
}

// Robustly weighted sums about the centroid c over all matches, in fixed chunks.
Partial Accumulate(const IcpProblem& p, double sigma, const Eigen::Vector3d& c) {
  const std::size_t n = p.source.size();
  const auto& target_points = p.target.points();
  const std::size_t chunks = ChunkCount(n, kChunk);
  std::vector<Partial> partial(chunks);
  ParallelForChunks(p.options.threads, chunks, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      Partial& s = partial[k];
      for (std::size_t i = k * kChunk; i < std::min(n, (k + 1) * kChunk); ++i) {
        const Match& m = p.matches[i];
        if (!m.valid) continue;
        const double w = Weight(p.options.kernel, m.residual, sigma);
        if (w <= 0.0) continue;
        const Eigen::Vector3d a = p.moved[i] - c;
        if (p.plane) {
          // r(x) = n.(s' + w x (s'-c) + v - q): J = [((s'-c) x n)^T, n^T]  (Chen & Medioni).
          const Eigen::Vector3d& nq = p.target_normals[m.target];
          Vector6d j;
          j << a.cross(nq), nq;
          s.h.noalias() += w * j * j.transpose();
          s.b.noalias() += w * m.residual * j;
        } else {
          const Eigen::Vector3d b = target_points[m.target] - c;
          s.w += w;
          s.sum_a += w * a;
          s.sum_b += w * b;
          s.cross.noalias() += w * b * a.transpose();
        }
      }
    }
  });
  Partial total;
  for (const Partial& s : partial) {
    total.h += s.h;
    total.b += s.b;
    total.w += s.w;
    total.sum_a += s.sum_a;
    total.sum_b += s.sum_b;
    total.cross += s.cross;
  }
  return total;
}

// Point-to-plane step from the normal equations; false when they have no positive eigenvalue.
bool SolvePointToPlane(const Partial& total, Eigen::Matrix3d* d_rot, Eigen::Vector3d* d_trans,
                       bool* degenerate) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(total.h);
  const double max_eig = eig.eigenvalues().maxCoeff();
  *degenerate = !(max_eig > 0.0) || eig.eigenvalues().minCoeff() < 1e-9 * max_eig;
  if (!(max_eig > 0.0)) return false;
  // Tiny damping keeps unobservable directions (planes, cylinders) where they are.
  const Vector6d x = -(total.h + 1e-9 * max_eig * Matrix6d::Identity()).ldlt().solve(total.b);
  *d_rot = QuaternionFromRotationVector(x.head<3>()).toRotationMatrix();
  *d_trans = x.tail<3>();
  return true;
}

// Point-to-point step; false when no match has a positive weight.
bool SolvePointToPoint(const Partial& total, Eigen::Matrix3d* d_rot, Eigen::Vector3d* d_trans,
                       bool* degenerate) {
  if (!(total.w > 0.0)) return false;
  // Weighted Horn/Umeyama (no scale): rotation from the SVD of the cross-covariance.
  const Eigen::Vector3d mean_a = total.sum_a / total.w, mean_b = total.sum_b / total.w;
  const Eigen::Matrix3d cov = total.cross / total.w - mean_b * mean_a.transpose();
  Eigen::Vector3d sv;
  *d_rot = HornRotation(cov, &sv);
  *d_trans = mean_b - *d_rot * mean_a;
  *degenerate = sv(1) < 1e-9 * sv(0);
  return true;
}

// Statistics at the returned pose: correspondences, kernel scale, inliers within 3 sigma, RMSEs.
void ReportFit(IcpProblem& p, IcpResult& result) {
  const std::size_t n = p.source.size();
  const auto& target_points = p.target.points();
  std::vector<double> abs_r = Associate(p, result.target_from_source);
  result.correspondences = abs_r.size();
  result.kernel_scale_mm = KernelScale(p.options, abs_r);
  double sum_sq = 0.0, sum_point_sq = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Match& m = p.matches[i];
    if (!m.valid || std::abs(m.residual) > 3.0 * result.kernel_scale_mm) continue;
    ++result.inliers;
    sum_sq += m.residual * m.residual;
    sum_point_sq += (p.moved[i] - target_points[m.target]).squaredNorm();
  }
  if (result.inliers > 0) {
    result.rmse_mm = std::sqrt(sum_sq / result.inliers);
    result.point_rmse_mm = std::sqrt(sum_point_sq / result.inliers);
  }
  result.inlier_fraction = n > 0 ? static_cast<double>(result.inliers) / n : 0.0;
  if (result.correspondences < p.options.min_correspondences) {
    result.termination = IcpTermination::kTooFewCorrespondences;
    result.converged = false;
  }
}

// psi'(r) = d(w(r) r)/dr, the slope of the kernel's influence function (Huber 1981, sec. 7.6):
// the estimator's Hessian weight, where IRLS uses w(r).
double InfluenceSlope(RobustKernel kernel, double r, double sigma) {
  const double a = std::abs(r);
  switch (kernel) {
    case RobustKernel::kNone:
      return 1.0;
    case RobustKernel::kHuber:
      return a <= 1.345 * sigma ? 1.0 : 0.0;
    case RobustKernel::kTukey: {
      const double c = 4.685 * sigma;
      if (a >= c) return 0.0;
      const double u2 = (r / c) * (r / c);
      return (1.0 - u2) * (1.0 - 5.0 * u2);
    }
    case RobustKernel::kGemanMcClure: {
      const double s2 = sigma * sigma, d = s2 + r * r;
      return s2 * s2 * (s2 - 3.0 * r * r) / (d * d * d);
    }
  }
  return 1.0;
}

// The group of source point `x`: its cube of side `block` (covariance_block_mm), packed into
// one key (21 bits per axis, cube indices offset to stay positive for |x| < 1e6 blocks).
std::uint64_t BlockKey(const Eigen::Vector3d& x, double block) {
  const auto axis = [&](double v) {
    const auto k = static_cast<std::int64_t>(std::floor(v / block)) + (std::int64_t{1} << 20);
    return static_cast<std::uint64_t>(std::clamp<std::int64_t>(k, 0, (1 << 21) - 1));
  };
  return (axis(x.x()) << 42) | (axis(x.y()) << 21) | axis(x.z());
}

// Sums of the sandwich estimator (file comment of icp.hpp) about the matched centroid c.
struct Sandwich {
  Matrix6d a = Matrix6d::Zero();  // sum J^T psi'(r) J: the estimator's Hessian
  Matrix6d b = Matrix6d::Zero();  // sum J^T psi psi^T J over independent residuals (no blocks)
  double weighted_sq = 0.0;       // sum w r^2
  std::size_t residuals = 0;      // scalar residuals m
  // With blocks: per group its gradient sum g = sum J^T psi and its share of a, A_g.
  std::map<std::uint64_t, std::pair<Vector6d, Matrix6d>> groups;  // ordered: no hash order
  // Declared model error: per cube its pose sensitivity s_g (icp.hpp file comment).
  std::map<std::uint64_t, Vector6d> model_groups;
};

// Adds source point i's sensitivity to an offset of the model surface along its normal.
void AddModelError(const IcpProblem& p, std::size_t i, const Vector6d& s_i, Sandwich* s) {
  if (p.options.model_error_sigma_mm <= 0.0) return;
  auto& g =
      s->model_groups
          .try_emplace(BlockKey(p.source[i], p.options.model_error_length_mm), Vector6d::Zero())
          .first->second;
  g += s_i;
}

// Adds one source point's Hessian share `a_i` and gradient `g_i` = J^T psi.
void AddResidual(const IcpProblem& p, std::size_t i, const Matrix6d& a_i, const Vector6d& g_i,
                 Sandwich* s) {
  s->a.noalias() += a_i;
  const double block = p.options.covariance_block_mm;
  if (block <= 0.0) {
    s->b.noalias() += g_i * g_i.transpose();
    return;
  }
  auto& group =
      s->groups.try_emplace(BlockKey(p.source[i], block), Vector6d::Zero(), Matrix6d::Zero())
          .first->second;
  group.first += g_i;
  group.second += a_i;
}

Sandwich AccumulateSandwich(const IcpProblem& p, double sigma, const Eigen::Vector3d& c) {
  const auto& target_points = p.target.points();
  Sandwich s;
  for (std::size_t i = 0; i < p.source.size(); ++i) {
    const Match& m = p.matches[i];
    if (!m.valid) continue;
    const double w = Weight(p.options.kernel, m.residual, sigma);
    if (w <= 0.0) continue;
    const double slope = InfluenceSlope(p.options.kernel, m.residual, sigma);
    const Eigen::Vector3d a = p.moved[i] - c;
    if (p.plane) {
      const Eigen::Vector3d& nq = p.target_normals[m.target];
      Vector6d j;
      j << a.cross(nq), nq;
      AddResidual(p, i, slope * j * j.transpose(), (w * m.residual) * j, &s);
      AddModelError(p, i, slope * j, &s);
      s.weighted_sq += w * m.residual * m.residual;
      s.residuals += 1;
    } else {
      // e = T s - q, de/dxi = [-[a]x, I]; psi(e) = w(|e|) e has the Jacobian
      // w I + (psi'(|e|) - w) e e^T / |e|^2 (the kernel acts on the distance |e|).
      const Eigen::Vector3d e = p.moved[i] - target_points[m.target];
      Eigen::Matrix<double, 3, 6> j;
      j << -Skew(a), Eigen::Matrix3d::Identity();
      Eigen::Matrix3d d_psi = w * Eigen::Matrix3d::Identity();
      if (e.squaredNorm() > 0.0) d_psi += (slope - w) * e * e.transpose() / e.squaredNorm();
      AddResidual(p, i, j.transpose() * d_psi * j, j.transpose() * (w * e), &s);
      if (!p.target_normals.empty()) {
        AddModelError(p, i, j.transpose() * (d_psi * p.target_normals[m.target]), &s);
      }
      s.weighted_sq += w * e.squaredNorm();
      s.residuals += 3;
    }
  }
  return s;
}

// The grouped gradient scatter with each group's gradient taken as if the group had been left
// out of the fit (CR3, the cluster jackknife; Bell & McCaffrey 2002): the fit absorbs part of a
// group's shared error into the pose, so its residuals understate that error, the more the
// larger the group's leverage A_g A^+. By the push-through identity the leave-one-group-out
// gradient is (I - A_g A^+)^-1 g. Times (G - 1) / G.
Matrix6d JackknifeScatter(const Sandwich& s, const Matrix6d& a_plus) {
  Matrix6d b = Matrix6d::Zero();
  for (const auto& [key, group] : s.groups) {
    const Matrix6d leverage = group.second * a_plus;
    const Eigen::PartialPivLU<Matrix6d> lu(Matrix6d::Identity() - leverage);
    Vector6d g = lu.solve(group.first);
    // A group that alone determines a direction (leverage ~1) cannot be left out: keep its
    // plain gradient there.
    if (!g.allFinite() || std::abs(lu.determinant()) < 1e-6) g = group.first;
    b.noalias() += g * g.transpose();
  }
  const double n = static_cast<double>(s.groups.size());
  return b * ((n - 1.0) / n);
}

// Pose covariance at the returned pose (file comment of icp.hpp), from the matches ReportFit
// left in `p` (associated at the returned pose) and its kernel scale.
void EstimateCovariance(const IcpProblem& p, IcpResult& result) {
  result.covariance = Matrix6d::Identity() * kIcpUnobservableVariance;
  result.covariance_valid = false;
  if (result.correspondences == 0) return;
  // Linearized about the matched centroid c (as the steps are), for conditioning; moved to the
  // target origin at the end.
  const Eigen::Vector3d c = MatchedCentroid(p);
  const Sandwich s = AccumulateSandwich(p, result.kernel_scale_mm, c);
  const bool blocks = p.options.covariance_block_mm > 0.0;
  if (s.residuals <= 6 || (blocks && s.groups.size() <= 6)) return;
  const double dof = static_cast<double>(s.residuals - 6);
  result.residual_sigma_mm = std::sqrt(s.weighted_sq / dof);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(s.a);
  const double max_eig = eig.eigenvalues().maxCoeff();
  if (!(max_eig > 0.0)) return;
  const Matrix6d& v = eig.eigenvectors();
  const Vector6d lambda = eig.eigenvalues();
  Vector6d inverse = Vector6d::Zero();  // A^+ in its eigenbasis
  bool observable = true;
  for (int k = 0; k < 6; ++k) {
    if (lambda(k) > 1e-9 * max_eig) {
      inverse(k) = 1.0 / lambda(k);
    } else {
      observable = false;
    }
  }
  // A^+ B A^+, B with the small-sample factor m / (m - 6) (HC1, MacKinnon & White 1985) for
  // independent residuals or the jackknife over groups; directions A does not determine get
  // only the placeholder variance.
  Matrix6d b = blocks ? JackknifeScatter(s, v * inverse.asDiagonal() * v.transpose())
                      : Matrix6d(s.b * (static_cast<double>(s.residuals) / dof));
  const double sigma_f = p.options.model_error_sigma_mm;
  for (const auto& [key, s_g] : s.model_groups)
    b.noalias() += sigma_f * sigma_f * s_g * s_g.transpose();
  Matrix6d middle = inverse.asDiagonal() * (v.transpose() * b * v) * inverse.asDiagonal();
  for (int k = 0; k < 6; ++k) {
    if (inverse(k) == 0.0) middle(k, k) = kIcpUnobservableVariance;
  }
  const Matrix6d about_c = v * middle * v.transpose();
  // A perturbation about c, p -> c + Exp(w)(p - c) + u, is Exp([w; u + c x w]) about the
  // origin: the adjoint of the translation by c.
  Eigen::Isometry3d at_c = Eigen::Isometry3d::Identity();
  at_c.translation() = c;
  result.covariance = ComposeCovariance(at_c, Matrix6d::Zero(), about_c);
  result.covariance_valid =
      observable && result.termination != IcpTermination::kTooFewCorrespondences;
}

}  // namespace

void IcpOptions::Check() const {
  auto positive = [](double v, const char* field) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw OptionError(std::string("IcpOptions.") + field + " = " + std::to_string(v) +
                        ": must be > 0");
  };
  if (!(kernel_scale_mm >= 0.0) || !std::isfinite(kernel_scale_mm)) {
    throw OptionError("IcpOptions.kernel_scale_mm = " + std::to_string(kernel_scale_mm) +
                      ": must be >= 0 mm (0 = from MAD)");
  }
  positive(min_kernel_scale_mm, "min_kernel_scale_mm");
  positive(max_correspondence_distance_mm, "max_correspondence_distance_mm");
  positive(translation_tolerance_mm, "translation_tolerance_mm");
  positive(rotation_tolerance_rad, "rotation_tolerance_rad");
  if (max_iterations < 1) throw OptionError("IcpOptions.max_iterations must be >= 1");
  if (min_correspondences < 3) throw OptionError("IcpOptions.min_correspondences must be >= 3");
  if (!(max_normal_angle_rad >= 0.0 && max_normal_angle_rad <= std::numbers::pi / 2)) {
    throw OptionError("IcpOptions.max_normal_angle_rad = " + std::to_string(max_normal_angle_rad) +
                      ": must be in [0, pi/2] rad (0 = no normal test)");
  }
  if (!(model_error_sigma_mm >= 0.0) || !std::isfinite(model_error_sigma_mm)) {
    throw OptionError("IcpOptions.model_error_sigma_mm = " + std::to_string(model_error_sigma_mm) +
                      ": must be >= 0 mm (0 = the model is exact)");
  }
  positive(model_error_length_mm, "model_error_length_mm");
  if (!(covariance_block_mm >= 0.0) || !std::isfinite(covariance_block_mm)) {
    throw OptionError("IcpOptions.covariance_block_mm = " + std::to_string(covariance_block_mm) +
                      ": must be >= 0 mm (0 = every residual independent)");
  }
}

const char* ToString(IcpTermination t) {
  switch (t) {
    case IcpTermination::kConverged:
      return "converged";
    case IcpTermination::kMaxIterations:
      return "max_iterations";
    case IcpTermination::kTooFewCorrespondences:
      return "too_few_correspondences";
  }
  return "unknown";
}

std::string IcpResult::Summary() const {
  std::ostringstream s;
  s << ToString(termination) << " after " << iterations << " iterations: rmse " << rmse_mm
    << " mm (point " << point_rmse_mm << " mm), " << inliers << "/" << correspondences
    << " inliers, sigma " << kernel_scale_mm << " mm" << (degenerate ? ", degenerate" : "")
    << (covariance_valid ? "" : ", no covariance");
  return s.str();
}

IcpResult AlignIcp(std::span<const Eigen::Vector3d> source, const KdTree& target,
                   std::span<const Eigen::Vector3d> target_normals,
                   const Eigen::Isometry3d& initial_target_from_source, const IcpOptions& options,
                   std::span<const Eigen::Vector3d> source_normals) {
  options.Check();
  const bool plane = options.metric == IcpMetric::kPointToPlane;
  if (plane && target_normals.size() != target.size()) {
    throw InputError("AlignIcp: point-to-plane needs one target normal per target point (" +
                     std::to_string(target_normals.size()) + " normals for " +
                     std::to_string(target.size()) + " points)");
  }
  const bool normal_test = options.max_normal_angle_rad > 0.0 && !source_normals.empty();
  if (normal_test &&
      (source_normals.size() != source.size() || target_normals.size() != target.size())) {
    throw InputError(
        "AlignIcp: the normal compatibility test needs one normal per source and "
        "target point (" +
        std::to_string(source_normals.size()) + " for " + std::to_string(source.size()) +
        " source, " + std::to_string(target_normals.size()) + " for " +
        std::to_string(target.size()) + " target points)");
  }
  IcpResult result;
  result.target_from_source = initial_target_from_source;
  const std::size_t n = source.size();
  IcpProblem problem{
      source,
      target,
      target_normals,
      options,
      plane,
      options.max_correspondence_distance_mm * options.max_correspondence_distance_mm,
      std::vector<Match>(n),
      std::vector<Eigen::Vector3d>(n),
      normal_test ? source_normals : std::span<const Eigen::Vector3d>{},
      normal_test ? std::cos(options.max_normal_angle_rad) : -1.0};

  result.termination = IcpTermination::kMaxIterations;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    std::vector<double> abs_r = Associate(problem, result.target_from_source);
    if (abs_r.size() < options.min_correspondences) {
      result.termination = IcpTermination::kTooFewCorrespondences;
      break;
    }
    const double sigma = KernelScale(options, abs_r);
    const Eigen::Vector3d c = MatchedCentroid(problem);
    const Partial total = Accumulate(problem, sigma, c);
    Eigen::Matrix3d d_rot = Eigen::Matrix3d::Identity();
    Eigen::Vector3d d_trans = Eigen::Vector3d::Zero();
    const bool solved = plane ? SolvePointToPlane(total, &d_rot, &d_trans, &result.degenerate)
                              : SolvePointToPoint(total, &d_rot, &d_trans, &result.degenerate);
    if (!solved) {
      result.termination = IcpTermination::kTooFewCorrespondences;
      break;
    }
    // Update: p -> c + dR (p - c) + dt, applied on the left of the current pose.
    Eigen::Isometry3d update = Eigen::Isometry3d::Identity();
    update.linear() = d_rot;
    update.translation() = c + d_trans - d_rot * c;
    result.target_from_source = Orthonormalized(update * result.target_from_source);
    ++result.iterations;
    // Step size: motion of the linearization centre (the source centroid) and the turn.
    const double turned = Eigen::AngleAxisd(d_rot).angle();
    if (d_trans.norm() < options.translation_tolerance_mm &&
        turned < options.rotation_tolerance_rad) {
      result.termination = IcpTermination::kConverged;
      break;
    }
  }
  result.converged = result.termination == IcpTermination::kConverged;
  ReportFit(problem, result);
  EstimateCovariance(problem, result);
  return result;
}

}  // namespace lasercell::registration
