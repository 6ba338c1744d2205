// CalibrateHalfSpheresInSweep: the composition of segmentation (sphere_segmentation.hpp) and
// calibration (half_sphere_calibration.hpp) that `lasercell calibrate spheres` runs.
#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <string>

#include "calib/half_sphere_calibration.hpp"
#include "core/error.hpp"
#include "core/provenance.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {
namespace {

std::string Num(double v, const char* format) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

// First-order move of a fitted sphere when its points move by dp_i (3 x K each): the fit's
// normal equations sum_i g_i (|p_i - c| - r) = 0 with g_i = [u_i; 1] (u_i the unit direction
// from the centre; without the 1 when the radius is fixed) give
//   d[c; r] = (sum_i g_i g_i^T)^-1 sum_i g_i u_i^T dp_i       over the fit's inliers.
// Rows 0-2: the centre, row 3: the radius (zero when fixed).
Eigen::Matrix<double, 4, Eigen::Dynamic> SphereResponse(
    const PointCloud& sweep, const SegmentedSphere& sphere, Eigen::Index modes,
    const std::function<Eigen::Matrix<double, 3, Eigen::Dynamic>(std::size_t)>& displace) {
  const bool free_radius = !sphere.fit.radius_fixed;
  const int n = free_radius ? 4 : 3;
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  Eigen::Matrix<double, 4, Eigen::Dynamic> rhs =
      Eigen::Matrix<double, 4, Eigen::Dynamic>::Zero(4, modes);
  for (std::size_t j = 0; j < sphere.indices.size(); ++j) {
    if (sphere.fit.outlier[j]) continue;
    const std::size_t i = sphere.indices[j];
    const Eigen::Vector3d u = (sweep.positions[i] - sphere.fit.center).normalized();
    Eigen::Vector4d g(u.x(), u.y(), u.z(), free_radius ? 1.0 : 0.0);
    normal += g * g.transpose();
    const Eigen::Matrix<double, 3, Eigen::Dynamic> dp = displace(i);
    LASERCELL_CHECK(dp.cols() == modes, "point_displacements changed its number of modes");
    rhs += g * (u.transpose() * dp);
  }
  Eigen::Matrix<double, 4, Eigen::Dynamic> out =
      Eigen::Matrix<double, 4, Eigen::Dynamic>::Zero(4, modes);
  out.topRows(n) = normal.topLeftCorner(n, n).ldlt().solve(rhs.topRows(n));
  return out;
}

// The calibration's response to each sensor mode: the swept spheres moved by +-1 sigma of the
// mode, calibrated again against the same touches; central difference of the left perturbation.
Eigen::Matrix<double, 6, Eigen::Dynamic> ModeResponse(const PointCloud& sweep,
                                                      const HalfSphereSweepResult& run,
                                                      const std::vector<SphereTouch>& touches,
                                                      const HalfSphereCalibrationOptions& options,
                                                      const HalfSphereSweepOptions& sweep_options) {
  const std::vector<SweptSphere> swept = SweptSpheresFrom(run.segmentation);
  const Eigen::Index modes = sweep_options.point_displacements(0).cols();
  std::vector<Eigen::Matrix<double, 4, Eigen::Dynamic>> response;
  for (const SegmentedSphere& s : run.segmentation.spheres) {
    response.push_back(SphereResponse(sweep, s, modes, sweep_options.point_displacements));
  }
  const Eigen::Isometry3d base_inverse = run.calibration.handling_base_from_sweep.inverse();
  Eigen::Matrix<double, 6, Eigen::Dynamic> out(6, modes);
  for (Eigen::Index k = 0; k < modes; ++k) {
    Vector6d xi[2];
    for (int side = 0; side < 2; ++side) {
      const double sign = side == 0 ? 1.0 : -1.0;
      std::vector<SweptSphere> moved = swept;
      for (std::size_t s = 0; s < moved.size(); ++s) {
        moved[s].center_in_sweep += sign * response[s].col(k).head<3>();
        moved[s].radius_mm += sign * response[s](3, k);
      }
      const HalfSphereCalibrationResult r = CalibrateHalfSpheres(moved, touches, options);
      xi[side] = RotationVectorTranslation(r.handling_base_from_sweep * base_inverse);
    }
    out.col(k) = 0.5 * (xi[0] - xi[1]);
  }
  return out;
}

// The radius tolerance's share of the calibration's covariance (HalfSphereSweepOptions::
// radius_tolerance_mm): per matched sphere, its true radius `sigma` larger moves the fitted
// centre by SphereResponse with every point pushed out by sigma along u, and the touched centre
// by sigma up; the rigid fit is redone at +-1 sigma (central difference), and the spheres'
// independent responses are squared and summed.
Matrix6d RadiusCovariance(const PointCloud& sweep, const HalfSphereSweepResult& run,
                          const std::vector<SphereTouch>& touches,
                          const HalfSphereCalibrationOptions& options, double sigma) {
  const std::vector<SweptSphere> swept = SweptSpheresFrom(run.segmentation);
  const Eigen::Isometry3d base_inverse = run.calibration.handling_base_from_sweep.inverse();
  const Eigen::Vector3d up = options.up_in_handling_base.normalized();
  Matrix6d covariance = Matrix6d::Zero();
  for (const HalfSphereResidual& matched : run.calibration.spheres) {
    const SegmentedSphere& sphere = run.segmentation.spheres[matched.swept];
    const auto outward = [&](std::size_t i) {
      Eigen::Matrix<double, 3, Eigen::Dynamic> dp(3, 1);
      dp.col(0) = sigma * (sweep.positions[i] - sphere.fit.center).normalized();
      return dp;
    };
    const Eigen::Vector3d shift = SphereResponse(sweep, sphere, 1, outward).col(0).head<3>();
    Vector6d xi[2];
    for (int side = 0; side < 2; ++side) {
      const double sign = side == 0 ? 1.0 : -1.0;
      std::vector<SweptSphere> moved = swept;
      moved[matched.swept].center_in_sweep += sign * shift;
      std::vector<SphereTouch> touched = touches;
      for (SphereTouch& t : touched) {
        if (t.sphere == matched.sphere) t.point_in_handling_base += sign * sigma * up;
      }
      const HalfSphereCalibrationResult r = CalibrateHalfSpheres(moved, touched, options);
      xi[side] = RotationVectorTranslation(r.handling_base_from_sweep * base_inverse);
    }
    const Vector6d column = 0.5 * (xi[0] - xi[1]);
    covariance += column * column.transpose();
  }
  return covariance;
}

}  // namespace

HalfSphereSweepResult CalibrateHalfSpheresInSweep(const PointCloud& sweep,
                                                  const SphereTouches& touches,
                                                  const HalfSphereSweepOptions& options,
                                                  const HalfSphereInputNames& names) {
  HalfSphereSweepResult run;
  run.radius_mm = options.radius_mm;
  if (run.radius_mm <= 0) {
    if (!touches.sphere_radius_mm) {
      throw InputError(names.touches + ": no sphere_radius_mm; give --radius-mm R");
    }
    run.radius_mm = *touches.sphere_radius_mm;
  }
  run.touch_sigma_mm =
      options.touch_sigma_mm > 0 ? options.touch_sigma_mm : touches.stated_sigma_mm;
  if (!std::isfinite(options.radius_tolerance_mm)) {
    throw OptionError(
        "HalfSphereSweepOptions.radius_tolerance_mm must be finite (< 0: the "
        "touches file's)");
  }
  run.radius_tolerance_mm = options.radius_tolerance_mm >= 0
                                ? options.radius_tolerance_mm
                                : touches.sphere_radius_tolerance_mm.value_or(0.0);

  // Segmentation: the spheres in the sweep, radius fixed unless asked otherwise.
  SphereSegmentationOptions seg_options;
  seg_options.radius_mm = run.radius_mm;
  seg_options.fix_radius = !options.free_radius;
  run.segmentation = SegmentSpheres(sweep, seg_options);
  const SphereSegmentationResult& seg = run.segmentation;
  if (seg.spheres.empty()) {
    run.failure =
        "no sphere of radius " + Num(run.radius_mm, "%g") + " mm found (" + seg.Summary() + ")";
    if (!options.sweep_unit_hint.empty()) run.failure += "; " + options.sweep_unit_hint;
    if (!seg.rejected.empty()) {
      run.failure += "; strongest candidate rejected: " + seg.rejected[0].reason;
    }
    return run;
  }

  // Calibration against the touches; its degeneracies name both inputs.
  HalfSphereCalibrationOptions calibration;
  calibration.up_in_handling_base = options.up_in_handling_base;
  calibration.touch_sigma_mm = run.touch_sigma_mm;
  try {
    run.calibration = CalibrateHalfSpheres(SweptSpheresFrom(seg), touches.touches, calibration);
  } catch (const OptionError&) {
    throw;
  } catch (const InputError& e) {
    throw InputError(names.sweep + " + " + names.touches + ": " + e.what());
  }
  run.up_in_handling_base = options.up_in_handling_base.normalized();
  // Warnings of the matched spheres' fits (small caps, correlated noise) join the result's.
  for (const auto& s : run.calibration.spheres) {
    for (const auto& w : seg.spheres[s.swept].fit.warnings) {
      run.calibration.warnings.push_back("sphere " + std::to_string(s.sphere) + ": " + w);
    }
  }
  if (!options.free_radius && run.radius_tolerance_mm > 0) {
    run.radius_covariance = RadiusCovariance(sweep, run, touches.touches, calibration,
                                             run.radius_tolerance_mm / std::sqrt(3.0));
    run.calibration.covariance += run.radius_covariance;
  }
  if (options.point_displacements) {
    run.mode_response = ModeResponse(sweep, run, touches.touches, calibration, options);
  }
  run.calibrated = true;
  return run;
}

void CheckHalfSphereEdgeFits(const FrameGraph& graph, const std::string& frame,
                             const std::string& cell_name) {
  if (!graph.HasFrame("handling_base") || !graph.HasFrame(frame)) return;
  for (const StaticEdge& e : graph.static_edges()) {
    if ((e.parent == "handling_base" && e.child == frame) ||
        (e.child == "handling_base" && e.parent == frame)) {
      return;  // our own edge: replaced
    }
  }
  if (graph.Connected("handling_base", frame)) {
    throw InputError(cell_name + ": handling_base and '" + frame +
                     "' are already connected through other edges (e.g. a hand-eye edge); the "
                     "half-sphere calibration holds only for the sweep it used: pass "
                     "--sweep-frame NAME to store it as a frame of its own (e.g. sweep_start)");
  }
}

EdgeProvenance HalfSphereProvenance(const HalfSphereCalibrationResult& result,
                                    const std::string& input_digest) {
  EdgeProvenance provenance;
  provenance.tool = std::string("lasercell calibrate spheres ") + LASERCELL_VERSION;
  provenance.date = UtcTimestampIso();
  provenance.input_digest = input_digest;
  provenance.residual_summary = "rms " + Num(result.fit.rms_mm, "%.4f") + " mm over " +
                                std::to_string(result.spheres.size()) + " spheres, chi2/dof " +
                                Num(result.fit.chi2, "%.3g") + "/" + std::to_string(result.fit.dof);
  return provenance;
}

}  // namespace lasercell::calib
