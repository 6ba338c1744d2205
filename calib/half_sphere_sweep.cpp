// CalibrateHalfSpheresInSweep: the composition of segmentation (sphere_segmentation.hpp) and
// calibration (half_sphere_calibration.hpp) that `lasercell calibrate spheres` runs.
#include <cstdio>
#include <string>

#include "calib/half_sphere_calibration.hpp"
#include "core/error.hpp"
#include "core/provenance.hpp"

namespace lasercell::calib {
namespace {

std::string Num(double v, const char* format) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
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
