#pragma once
// `lasercell calibrate handeye-laser --profiles ... --poses ...`: the eye-in-hand laser
// calibration from one calibrated profile per robot pose across a fixed sphere
// (calib/sphere_section_hand_eye.hpp), for profilers that deliver calibrated points and robots
// that report Cartesian poses. Registered by cmd_calibrate_joints.cpp beside the sweep variant.
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace lasercell::tools {

/// Flags of the sections variant (the shared ones are copied in by the caller).
struct HandEyeSectionArgs {
  std::vector<std::string> profiles;  ///< One profile file per pose, in pose order.
  std::string poses, pose_format, sphere_side;
  bool estimate_radius = false;
  double radius_mm = 0;
  std::string cell, output, json, report, robot = "vision_robot", sensor_frame = "sensor";
};

/// Adds --profiles, --poses, --pose-format, --sphere-side, --estimate-radius to `cmd`.
void AddHandEyeSectionOptions(CLI::App* cmd, HandEyeSectionArgs& a);
/// True when the sections variant was asked for (--profiles or --poses given).
bool HandEyeSectionsRequested(const HandEyeSectionArgs& a);
/// Reads, calibrates, writes the JSON / report and, with --cell, the flange <-> sensor edge.
void RunHandEyeSections(const HandEyeSectionArgs& a);

}  // namespace lasercell::tools
