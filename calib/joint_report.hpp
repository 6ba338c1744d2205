#pragma once
// Result files of the sphere-sweep robot calibrations: the versioned JSON and the HTML report
// (core/html_report.hpp) of joint identification (format lasercell.joint_calibration, version 1)
// and of the eye-in-hand laser calibration (format lasercell.laser_hand_eye, version 1). Fills
// them only; tools write them.

#include <nlohmann/json.hpp>
#include <string>

#include "calib/joint_identification.hpp"
#include "calib/laser_hand_eye.hpp"
#include "core/html_report.hpp"

namespace lasercell::calib {

/// What the result files say about the run's inputs.
struct SphereSweepRun {
  std::string robot;        ///< Robot name in the cell, e.g. vision_robot.
  std::string sweeps_path;  ///< The sweep list (records/sphere_sweeps.yaml).
  std::string sweep_set;    ///< The set used, e.g. joint_poses.
  std::size_t sweep_count = 0;
  std::string touches_path;    ///< Touches that fixed the sphere centres; empty: centres free.
  bool with_hand_eye = false;  ///< Joints: flange_from_sensor estimated too.
  bool dh_deltas = false;      ///< Joints: a, d, alpha estimated too.
};

/// The lasercell.joint_calibration v1 document: offsets (deg), optional DH parameters and
/// hand-eye pose, spheres, per-sweep residuals, observability, covariance, warnings.
nlohmann::json JointCalibrationJson(const JointIdentificationResult& result,
                                    const SphereSweepRun& run);
/// The joint-identification report: summary, offsets, per-pose errors, residuals,
/// observability, correlation table.
report::HtmlReport JointCalibrationReport(const JointIdentificationResult& result,
                                          const SphereSweepRun& run);

/// The lasercell.laser_hand_eye v1 document.
nlohmann::json LaserHandEyeJson(const LaserHandEyeResult& result, const SphereSweepRun& run);
/// The laser hand-eye report.
report::HtmlReport LaserHandEyeReport(const LaserHandEyeResult& result, const SphereSweepRun& run);

}  // namespace lasercell::calib
