#pragma once
// The HTML report of a camera calibration (core/html_report.hpp): summary, warnings, intrinsics
// with 1 sigma, residual histogram, residual vectors over the image, per-image RMS, coverage of
// the image by the observations, projection uncertainty over the image, per-image table.
// Fills the report only; tools write it.

#include <string>

#include "calib/intrinsics.hpp"
#include "core/html_report.hpp"

namespace lasercell::calib {

/// Builds the report for `result` (from CalibrateIntrinsics). `title` heads the page, `inputs`
/// is one line describing the inputs (images glob, board).
report::HtmlReport IntrinsicsReport(const IntrinsicsResult& result, const std::string& title,
                                    const std::string& inputs);

}  // namespace lasercell::calib
