#include "calib/half_sphere_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/pose_covariance.hpp"

namespace lasercell::calib {
namespace {

std::string Mm(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.3g mm", v);
  return buf;
}

// Enumerates injective maps from {0..m-1} into {0..k-1} (m <= k), calling f(map).
template <typename F>
void ForEachInjection(std::size_t m, std::size_t k, F&& f) {
  std::vector<std::size_t> map(m);
  std::vector<std::uint8_t> taken(k, 0);
  auto rec = [&](auto&& self, std::size_t i) -> void {
    if (i == m) {
      f(map);
      return;
    }
    for (std::size_t j = 0; j < k; ++j) {
      if (taken[j]) continue;
      taken[j] = 1;
      map[i] = j;
      self(self, i + 1);
      taken[j] = 0;
    }
  };
  rec(rec, 0);
}

// Inputs that cannot determine the calibration: fewer than 3 spheres on either side, more than
// can be matched by enumeration, a sphere touched twice.
void CheckSphereCounts(std::size_t k, const std::vector<SphereTouch>& touches) {
  const std::size_t m = touches.size();
  if (std::min(k, m) < 3) {
    const bool few_touches = m <= k;
    throw InputError(
        "half-sphere calibration: " +
        (few_touches
             ? std::to_string(m) + " sphere touch" + (m == 1 ? "" : "es")
             : std::to_string(k) + " sphere" + (k == 1 ? "" : "s") + " found in the sweep") +
        ": at least 3 non-collinear spheres must be both swept and touched (fewer leave the "
        "rotation unobservable)");
  }
  if (std::max(k, m) > 10) {
    throw InputError("half-sphere calibration: " + std::to_string(std::max(k, m)) +
                     " spheres; at most 10 can be matched automatically");
  }
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      if (touches[i].sphere == touches[j].sphere) {
        throw InputError("half-sphere calibration: sphere " + std::to_string(touches[i].sphere) +
                         " is touched twice");
      }
    }
  }
}

// The matched spheres of one calibration: the swept spheres, the touches, and where the touched
// centres are (top - (r + tip) * up).
struct Matching {
  const std::vector<SweptSphere>& swept;
  const std::vector<SphereTouch>& touches;
  const HalfSphereCalibrationOptions& options;
  Eigen::Vector3d up;  // unit
  Eigen::Vector3d TouchedCenter(std::size_t t, double r) const {
    return touches[t].point_in_handling_base - (r + options.tool_tip_radius_mm) * up;
  }
};

// The chosen assignment: (touch, swept) pairs sorted by touch, and the scores.
struct Correspondence {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  double best_rms_mm = 0;
  double runner_up_rms_mm = 0;  // infinity when there is no other assignment
};

// Correspondence by the closed-form rigid fit's RMS over every injective assignment of the
// smaller set into the larger. Collinear layouts, touches that match no assignment and two
// assignments that both match (a symmetric layout) are InputErrors naming the degeneracy.
Correspondence MatchTouches(const Matching& mt) {
  const std::vector<SweptSphere>& swept = mt.swept;
  const HalfSphereCalibrationOptions& options = mt.options;
  const std::size_t k = swept.size(), m = mt.touches.size();
  // For scoring, the touched centres use the mean swept radius (the spheres are all alike); the
  // radius of each is known after matching.
  double mean_r = 0;
  for (const auto& s : swept) mean_r += s.radius_mm;
  mean_r /= static_cast<double>(k);
  const bool touches_smaller = m <= k;
  const std::size_t small = std::min(k, m), large = std::max(k, m);
  double best = std::numeric_limits<double>::infinity(), second = best;
  std::vector<std::size_t> best_map;
  ForEachInjection(small, large, [&](const std::vector<std::size_t>& map) {
    std::vector<Eigen::Vector3d> src, dst;
    for (std::size_t i = 0; i < small; ++i) {
      const std::size_t t = touches_smaller ? i : map[i];
      const std::size_t s = touches_smaller ? map[i] : i;
      src.push_back(swept[s].center_in_sweep);
      dst.push_back(mt.TouchedCenter(t, mean_r));
    }
    if (MaxDistanceFromLine(src) < options.rigid.min_off_line_mm) return;  // reported below
    const Eigen::Isometry3d t = HornRigidTransform(src, dst);
    double ss = 0;
    for (std::size_t i = 0; i < small; ++i) ss += (dst[i] - t * src[i]).squaredNorm();
    const double rms = std::sqrt(ss / static_cast<double>(small));
    if (rms < best) {
      second = best;
      best = rms;
      best_map = map;
    } else if (rms < second) {
      second = rms;
    }
  });
  if (best_map.empty()) {
    // Every assignment was collinear: let the rigid fit name the degeneracy.
    std::vector<Eigen::Vector3d> src, dst;
    for (std::size_t i = 0; i < small; ++i) {
      src.push_back(swept[i].center_in_sweep);
      dst.push_back(mt.TouchedCenter(i, mean_r));
    }
    RigidFitOptions r = options.rigid;
    r.item_name = "sphere";
    FitRigidTransform(src, dst, {}, {}, r);
    throw InputError("half-sphere calibration: the spheres are collinear");
  }
  if (best > options.max_match_rms_mm) {
    throw InputError(
        "half-sphere calibration: the touched spheres do not match the swept ones "
        "(best assignment leaves " +
        Mm(best) + " rms > " + Mm(options.max_match_rms_mm) +
        "): check the sphere radius, the touches' units and that the same spheres "
        "were swept and touched");
  }
  if (second <= options.max_match_rms_mm) {
    throw InputError(
        "half-sphere calibration: ambiguous correspondence between touches and swept "
        "spheres (two assignments fit: " +
        Mm(best) + " and " + Mm(second) +
        " rms): the layout is symmetric; place the spheres at different heights or "
        "distances");
  }
  Correspondence c;
  c.best_rms_mm = best;
  c.runner_up_rms_mm = second;
  for (std::size_t i = 0; i < small; ++i) {
    const std::size_t t = touches_smaller ? i : best_map[i];
    const std::size_t s = touches_smaller ? best_map[i] : i;
    c.pairs.emplace_back(t, s);
  }
  std::sort(c.pairs.begin(), c.pairs.end());
  return c;
}

// The weighted rigid fit of the matched swept centres to the touched ones (rigid_fit.hpp); with
// fitted radii, refined on the tops. `centers_hb` receives the touched centres.
RigidFitResult FitMatched(const Matching& mt, const Correspondence& c,
                          std::vector<Eigen::Vector3d>* centers_hb) {
  const std::vector<SweptSphere>& swept = mt.swept;
  const HalfSphereCalibrationOptions& options = mt.options;
  const Eigen::Vector3d& up = mt.up;
  std::vector<Eigen::Vector3d> src, dst;
  std::vector<Eigen::Matrix3d> src_cov, dst_cov;
  const double s2 = options.touch_sigma_mm * options.touch_sigma_mm;
  for (const auto& [t, s] : c.pairs) {
    src.push_back(swept[s].center_in_sweep);
    src_cov.push_back(swept[s].covariance);
    centers_hb->push_back(mt.TouchedCenter(t, swept[s].radius_mm));
    dst.push_back(centers_hb->back());
    dst_cov.push_back(s2 * Eigen::Matrix3d::Identity() +
                      swept[s].radius_sigma_mm * swept[s].radius_sigma_mm * up * up.transpose());
  }
  RigidFitOptions rigid = options.rigid;
  rigid.item_name = "sphere";
  RigidFitResult fit = FitRigidTransform(src, dst, src_cov, dst_cov, rigid);
  bool free_radius = false;
  for (const auto& [t, s] : c.pairs) free_radius = free_radius || swept[s].radius_sigma_mm > 0;
  if (!free_radius) return fit;
  // A fitted radius is correlated with the centre (on a cap seen from above the top point is
  // better known than either). Fit the tops instead: top_in_sweep = c + (r + tip) u with u =
  // R^T up from the previous estimate, covariance [I u] Cov(c, r) [I u]^T, against the touches
  // themselves (sigma_touch^2 I). Two rounds: u moves by the rotation error only.
  for (int round = 0; round < 2; ++round) {
    const Eigen::Vector3d u = fit.target_from_source.linear().transpose() * up;
    for (std::size_t i = 0; i < c.pairs.size(); ++i) {
      const SweptSphere& sw = swept[c.pairs[i].second];
      src[i] = sw.center_in_sweep + (sw.radius_mm + options.tool_tip_radius_mm) * u;
      Eigen::Matrix<double, 3, 4> j;
      j << Eigen::Matrix3d::Identity(), u;
      Eigen::Matrix4d c4 = Eigen::Matrix4d::Zero();
      c4.topLeftCorner<3, 3>() = sw.covariance;
      c4.block<3, 1>(0, 3) = sw.center_radius_covariance;
      c4.block<1, 3>(3, 0) = sw.center_radius_covariance.transpose();
      c4(3, 3) = sw.radius_sigma_mm * sw.radius_sigma_mm;
      src_cov[i] = j * c4 * j.transpose();
      dst[i] = mt.touches[c.pairs[i].first].point_in_handling_base;
      dst_cov[i] = s2 * Eigen::Matrix3d::Identity();
    }
    fit = FitRigidTransform(src, dst, src_cov, dst_cov, rigid);
  }
  return fit;
}

// Unmatched spheres and touches, a rigid fit that did not converge, and a chi2 beyond the
// stated sigmas: the result's warnings.
void AddWarnings(const Matching& mt, const Correspondence& c, HalfSphereCalibrationResult* r) {
  std::vector<std::uint8_t> swept_used(mt.swept.size(), 0), touch_used(mt.touches.size(), 0);
  for (const auto& [t, s] : c.pairs) swept_used[s] = touch_used[t] = 1;
  for (std::size_t s = 0; s < mt.swept.size(); ++s) {
    if (!swept_used[s]) r->unmatched_swept.push_back(s);
  }
  for (std::size_t t = 0; t < mt.touches.size(); ++t) {
    if (!touch_used[t]) r->unmatched_touches.push_back(mt.touches[t].sphere);
  }
  if (!r->unmatched_swept.empty()) {
    r->warnings.push_back(std::to_string(r->unmatched_swept.size()) +
                          " sphere(s) found in the sweep were not touched");
  }
  if (!r->unmatched_touches.empty()) {
    r->warnings.push_back(std::to_string(r->unmatched_touches.size()) +
                          " touched sphere(s) were not found in the sweep");
  }
  if (!r->fit.converged) {
    r->warnings.push_back("the weighted rigid fit did not converge in " +
                          std::to_string(r->fit.iterations) +
                          " iterations (RigidFitOptions.max_iterations): the pose is the last "
                          "iterate");
  }
  // chi2 with 3n - 6 dof: a p-value below 0.1 % means the stated sigmas are too small.
  if (r->fit.dof > 0) {
    const double z = (r->fit.chi2 - r->fit.dof) / std::sqrt(2.0 * r->fit.dof);
    if (z > 3.1) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "chi2 %.3g for %d dof: the residuals exceed the stated touch sigma and fit "
                    "covariances; the reported 1-sigma is optimistic",
                    r->fit.chi2, r->fit.dof);
      r->warnings.push_back(buf);
    }
  }
}

}  // namespace

void HalfSphereCalibrationOptions::Check() const {
  if (!up_in_handling_base.allFinite() || up_in_handling_base.norm() < 1e-9) {
    throw OptionError("HalfSphereCalibrationOptions.up_in_handling_base must be a non-zero vector");
  }
  if (!(touch_sigma_mm > 0) || !std::isfinite(touch_sigma_mm)) {
    throw OptionError("HalfSphereCalibrationOptions.touch_sigma_mm must be positive");
  }
  if (!(tool_tip_radius_mm >= 0) || !std::isfinite(tool_tip_radius_mm)) {
    throw OptionError("HalfSphereCalibrationOptions.tool_tip_radius_mm must be >= 0");
  }
  if (!(max_match_rms_mm > 0)) {
    throw OptionError("HalfSphereCalibrationOptions.max_match_rms_mm must be positive");
  }
  rigid.Check();
}

std::vector<SweptSphere> SweptSpheresFrom(const SphereSegmentationResult& segmentation) {
  std::vector<SweptSphere> out;
  for (const SegmentedSphere& s : segmentation.spheres) {
    out.push_back({s.fit.center, s.fit.CenterCovariance(), s.fit.radius_mm, s.fit.radius_sigma_mm,
                   s.fit.covariance.block<3, 1>(0, 3)});
  }
  return out;
}

HalfSphereCalibrationResult CalibrateHalfSpheres(const std::vector<SweptSphere>& swept,
                                                 const std::vector<SphereTouch>& touches,
                                                 const HalfSphereCalibrationOptions& options) {
  options.Check();
  CheckSphereCounts(swept.size(), touches);
  const Matching mt{swept, touches, options, options.up_in_handling_base.normalized()};
  const Correspondence c = MatchTouches(mt);

  HalfSphereCalibrationResult result;
  result.match_rms_mm = c.best_rms_mm;
  result.runner_up_match_rms_mm = std::isfinite(c.runner_up_rms_mm) ? c.runner_up_rms_mm : 0.0;
  std::vector<Eigen::Vector3d> centers_hb;
  result.fit = FitMatched(mt, c, &centers_hb);
  result.handling_base_from_sweep = result.fit.target_from_source;
  result.covariance = result.fit.covariance;
  for (std::size_t i = 0; i < c.pairs.size(); ++i) {
    const auto [t, s] = c.pairs[i];
    HalfSphereResidual r;
    r.sphere = touches[t].sphere;
    r.swept = s;
    r.center_in_sweep = swept[s].center_in_sweep;
    r.center_in_handling_base = centers_hb[i];
    r.residual_mm = result.fit.residuals_mm[i];
    r.residual_norm_mm = result.fit.residual_norms_mm[i];
    r.mahalanobis = result.fit.mahalanobis[i];
    r.radius_mm = swept[s].radius_mm;
    result.spheres.push_back(r);
  }
  AddWarnings(mt, c, &result);
  return result;
}

StaticEdge HalfSphereEdge(const HalfSphereCalibrationResult& result, const std::string& sweep_frame,
                          const EdgeProvenance& provenance) {
  StaticEdge edge;
  edge.parent = "handling_base";
  edge.child = sweep_frame;
  edge.SetParentFromChild(result.handling_base_from_sweep);
  edge.provenance = provenance;
  edge.covariance = result.covariance;
  return edge;
}

std::string HalfSphereCalibrationResult::Summary() const {
  const Eigen::Vector3d r = RotationSigmaDeg(covariance), t = TranslationSigmaMm(covariance);
  char buf[300];
  std::snprintf(buf, sizeof buf,
                "handling_base_from_sweep over %zu spheres: rms %.4f mm, max %.4f mm, chi2/dof "
                "%.3g/%d, 1-sigma %.4f deg / %.4f mm",
                spheres.size(), fit.rms_mm,
                fit.residual_norms_mm.empty()
                    ? 0.0
                    : *std::max_element(fit.residual_norms_mm.begin(), fit.residual_norms_mm.end()),
                fit.chi2, fit.dof, r.norm(), t.norm());
  return buf;
}

}  // namespace lasercell::calib
