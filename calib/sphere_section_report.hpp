#pragma once
// Result files of the eye-in-hand calibration from sphere sections
// (calib/sphere_section_hand_eye.hpp): the versioned JSON (format
// lasercell.laser_hand_eye_sections, version 1) and the HTML report (core/html_report.hpp).
// Fills them only; tools write them. Units mm and deg as the field names say.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib/sphere_section_hand_eye.hpp"
#include "core/html_report.hpp"

namespace lasercell::calib {

/// What the result files say about the run's inputs.
struct SphereSectionRun {
  std::string poses_path;                  ///< The robot pose file.
  std::string pose_format;                 ///< Its format (e.g. xyzwpr).
  std::vector<std::string> profile_paths;  ///< One profile per pose, in pose order.
  SphereSectionHandEyeOptions options;     ///< As used.
};

/// The lasercell.laser_hand_eye_sections v1 document: the hand-eye pose and covariance, the
/// sphere, the centre spread and leave-one-pose-out scores, one entry per profile, warnings.
nlohmann::json SphereSectionHandEyeJson(const SphereSectionHandEyeResult& result,
                                        const SphereSectionRun& run);
/// The report: summary, per-profile table (circle, centre distance, leave-one-out), bars of the
/// centre distances, warnings.
report::HtmlReport SphereSectionHandEyeReport(const SphereSectionHandEyeResult& result,
                                              const SphereSectionRun& run);

}  // namespace lasercell::calib
