#pragma once
// The report of `lasercell bench registration` (bench_report.cpp): the Markdown table of every
// method's stage times and top-pose errors against the reference, its JSON rows, and lasercell's
// speed-up over OpenCV. Units: mm, deg in the table; times are milliseconds.
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <vector>

#include "tools/bench_registration.hpp"

namespace lasercell::tools {

/// Prints the table (header, one row per method, the reference pose's row, then each method's
/// note) and returns one JSON object per row: the times, the top pose's verdict ("<= 2 mm",
/// "near" within `correct_mm`, "WRONG", "none"), its errors and scene_from_model (4x4 row-major).
nlohmann::json PrintRegistrationTable(const std::vector<BenchRow>& rows,
                                      const PoseEvaluator& evaluate,
                                      const Eigen::Isometry3d& reference, double correct_mm);

/// Prints how much faster `ours` is than each OpenCV "+ ICP" row with a pose, in wall and CPU
/// time.
void PrintSpeedupsOverOpenCv(const std::vector<BenchRow>& rows, const BenchRow& ours,
                             const PoseEvaluator& evaluate);

}  // namespace lasercell::tools
