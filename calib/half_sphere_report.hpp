#pragma once
// What a half-sphere calibration writes besides the cell file: the result JSON (format
// `lasercell.calibration_spheres`, version 1) and the HTML report (core/html_report.hpp).
// Both describe one CalibrateHalfSpheresInSweep run; they fill documents only, tools write them.

#include <nlohmann/json.hpp>
#include <string>

#include "calib/half_sphere_calibration.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"

namespace lasercell::calib {

/// The result JSON (`lasercell.calibration_spheres` v1): the edge handling_base <- sweep frame
/// with its pose {translation_mm, rotation_wxyz}, 1-sigma and 6x6 covariance, the rigid fit's
/// rms/chi2/dof, the correspondence scores, per matched sphere its centres, residual and fit,
/// the segmentation's rejected candidates, warnings and summary. `edge` is the edge written to
/// the cell (HalfSphereEdge): its provenance digest is recorded.
nlohmann::json HalfSphereResultJson(const HalfSphereSweepResult& result,
                                    const HalfSphereInputNames& inputs, const StaticEdge& edge);

/// The HTML report: result table, per-sphere residuals (table and bars), each sphere fit's
/// residual histogram, the 6x6 covariance and the rejected sphere candidates.
report::HtmlReport HalfSphereReport(const HalfSphereSweepResult& result,
                                    const HalfSphereInputNames& inputs);

}  // namespace lasercell::calib
