#pragma once
// The HTML report of a job run (core/html_report.hpp): summary, an interactive 3D view of the
// sweep (decimated), the posed part meshes, the grasp frames and the ROI, and tables of poses,
// 1-sigma uncertainty, support, graspability, models and per-stage timings. Written by the
// tools (report::WriteHtmlReport); the meshes are in the result when the job ran with
// JobRunOptions::load_meshes.

#include "core/html_report.hpp"
#include "localize/job_run.hpp"

namespace lasercell::localize {

/// The report of `result`. Throws FileError when the 3D view's script (Debian libjs-three) is
/// not installed.
report::HtmlReport JobReport(const JobResult& result);

}  // namespace lasercell::localize
