// Touches file (format lasercell.touches, version 1), as the simulator writes records/touches.yaml
// (datasets/calibration_captures.cpp TouchesRecordYaml):
//   format: lasercell.touches
//   version: 1
//   robot: handling_robot
//   frame: handling_base
//   handling_flange_from_tool_tip: {translation_mm: [..], rotation_wxyz: [..]}   (optional)
//   stated_sigma_mm: 0.05                                                        (optional)
//   sphere_radius_mm: 25                                                         (optional)
//   sphere_radius_tolerance_mm: 0.05    # +- about sphere_radius_mm              (optional)
//   touches:
//     - {sphere: 0, point_in_handling_base: [x, y, z], joints_rad: [..] or null}
// Read through yaml::Fields: unknown fields are errors with the line (a `*_m` or `*_deg` field
// is another unit, not a typo to skip), joints beyond 2 pi look like degrees, a radius below
// 1 mm looks like metres.
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>

#include "calib/half_sphere_calibration.hpp"
#include "core/error.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell::calib {
namespace {

SphereTouch ReadTouch(yaml::Fields& e) {
  e.Known({"sphere", "point_in_handling_base", "joints_rad"});
  e.Done();
  SphereTouch touch;
  e.ReadRequired("sphere", &touch.sphere);
  if (touch.sphere < 0) e.Fail("sphere", "must be a non-negative integer");
  e.ReadRequired("point_in_handling_base", &touch.point_in_handling_base);
  std::vector<double> joints;
  if (e.ReadRadians("joints_rad", &joints)) touch.joints_rad = std::move(joints);
  return touch;
}

// Mixed units: a point two orders of magnitude nearer the robot base than the others is in
// metres among millimetres (a robot's reach is 100 mm to 3 m; its base origin is never touched).
void CheckUnits(const SphereTouches& t, yaml::Fields& top, std::vector<yaml::Fields>& items) {
  if (t.touches.empty()) return;
  double largest = 0;
  for (const auto& touch : t.touches) {
    largest = std::max(largest, touch.point_in_handling_base.norm());
  }
  for (std::size_t i = 0; i < t.touches.size(); ++i) {
    const double n = t.touches[i].point_in_handling_base.norm();
    if (largest > 50.0 && n < largest / 50.0) {
      items[i].Fail("point_in_handling_base",
                    "is " + std::to_string(n) + " from the base while another is " +
                        std::to_string(largest) +
                        ": mixed units (metres among millimetres?); give every point in mm");
    }
  }
  if (largest < 10.0) {
    top.Fail("touches",
             ": every touch lies within 10 mm of the robot base: the points look like "
             "metres; give millimetres");
  }
}

}  // namespace

SphereTouches ParseTouchesYaml(const std::string& text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FileError(name, std::string("not valid YAML: ") + e.what());
  }
  if (!root.IsMap()) {
    throw FileError(name,
                    "is not a touches file (expected a mapping starting with 'format: "
                    "lasercell.touches')");
  }
  yaml::Fields top(root, "", name, yaml::ErrorKind::kFile);
  top.Known({"format", "version", "robot", "frame", "handling_flange_from_tool_tip",
             "stated_sigma_mm", "sphere_radius_mm", "sphere_radius_tolerance_mm", "touches"});
  top.Done();
  top.RequireFormat("lasercell.touches", 1);
  SphereTouches t;
  top.Read("robot", &t.robot);
  if (top.Read("frame", &t.frame) && t.frame != "handling_base") {
    top.Fail("frame", "is '" + t.frame + "': touches must be given in handling_base");
  }
  if (top.Read("stated_sigma_mm", &t.stated_sigma_mm) && !(t.stated_sigma_mm > 0)) {
    top.Fail("stated_sigma_mm", "must be positive");
  }
  double radius = 0;
  if (top.ReadMillimetres("sphere_radius_mm", &radius, 1.0)) t.sphere_radius_mm = radius;
  double tolerance = 0;
  if (top.Read("sphere_radius_tolerance_mm", &tolerance)) {
    if (!(tolerance >= 0 && tolerance <= 0.1 * t.sphere_radius_mm.value_or(1e9) &&
          std::isfinite(tolerance))) {
      top.Fail("sphere_radius_tolerance_mm",
               "must be >= 0 mm and at most a tenth of sphere_radius_mm (got " +
                   std::to_string(tolerance) + ")");
    }
    t.sphere_radius_tolerance_mm = tolerance;
  }
  Eigen::Isometry3d tool;
  if (top.ReadPose("handling_flange_from_tool_tip", &tool)) t.handling_flange_from_tool_tip = tool;
  if (!top.Has("touches")) {
    top.Fail("touches", "is required: a list of {sphere, point_in_handling_base, joints_rad}");
  }
  std::vector<yaml::Fields> items = top.List("touches");
  std::set<int> labels;
  for (yaml::Fields& e : items) {
    const SphereTouch touch = ReadTouch(e);
    if (!labels.insert(touch.sphere).second) {
      e.Fail("sphere", "repeats a label: sphere " + std::to_string(touch.sphere) +
                           " is touched twice (give one touch per sphere)");
    }
    t.touches.push_back(touch);
  }
  CheckUnits(t, top, items);
  return t;
}

}  // namespace lasercell::calib
