// Touches file (format lasercell.touches, version 1), as the simulator writes records/touches.yaml
// (datasets/calibration_captures.cpp TouchesRecordYaml):
//   format: lasercell.touches
//   version: 1
//   robot: handling_robot
//   frame: handling_base
//   handling_flange_from_tool_tip: {translation_mm: [..], rotation_wxyz: [..]}   (optional)
//   stated_sigma_mm: 0.05                                                        (optional)
//   sphere_radius_mm: 25                                                         (optional)
//   touches:
//     - {sphere: 0, point_in_handling_base: [x, y, z], joints_rad: [..] or null}
// Unknown fields are errors (a `*_m` or `*_deg` field is another unit, not a typo to skip).
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <set>
#include <string_view>

#include "calib/half_sphere_calibration.hpp"
#include "core/error.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {
namespace {

constexpr std::array<std::string_view, 8> kTop = {
    "format", "version", "robot", "frame", "handling_flange_from_tool_tip", "stated_sigma_mm",
    "sphere_radius_mm", "touches"};
constexpr std::array<std::string_view, 3> kTouch = {"sphere", "point_in_handling_base",
                                                    "joints_rad"};

class TouchReader {
 public:
  explicit TouchReader(std::string name) : name_(std::move(name)) {}

  [[noreturn]] void Fail(const std::string& problem, const YAML::Node& node) const {
    const int line = node.Mark().line;
    throw FileError(name_, (line >= 0 ? "line " + std::to_string(line + 1) + ": " : "") + problem);
  }

  template <std::size_t N>
  void CheckFields(const YAML::Node& map, const std::array<std::string_view, N>& allowed,
                   const std::string& where) const {
    for (const auto& kv : map) {
      const std::string key = kv.first.as<std::string>();
      if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
      std::string hint;
      for (const char* suffix : {"_m", "_cm", "_in", "_deg", "_um", "_inch"}) {
        const std::string s(suffix);
        if (key.size() > s.size() && key.compare(key.size() - s.size(), s.size(), s) == 0) {
          hint = " (a field in '" + s.substr(1) + "': lasercell files are in mm and rad)";
        }
      }
      std::string list;
      for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      Fail("unknown field '" + key + "' in " + where + hint + "; allowed: " + list, kv.first);
    }
  }

  double Number(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) Fail(what + " must be a number", node);
    try {
      const double v = node.as<double>();
      if (!std::isfinite(v)) Fail(what + " must be finite", node);
      return v;
    } catch (const YAML::Exception&) {
      Fail(what + " must be a number, not '" + node.Scalar() + "'", node);
    }
  }

  std::vector<double> Numbers(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence()) Fail(what + " must be a list of numbers", node);
    std::vector<double> v;
    for (std::size_t i = 0; i < node.size(); ++i) {
      v.push_back(Number(node[i], what + "[" + std::to_string(i) + "]"));
    }
    return v;
  }

  SphereTouches Read(const YAML::Node& root) {
    if (!root.IsMap()) {
      throw FileError(name_, "is not a touches file (expected a mapping starting with 'format: "
                             "lasercell.touches')");
    }
    CheckFields(root, kTop, "the top level");
    if (!root["format"] || root["format"].Scalar() != "lasercell.touches") {
      Fail("format must be 'lasercell.touches'", root["format"] ? root["format"] : root);
    }
    if (!root["version"] || Number(root["version"], "version") != 1) {
      Fail("unsupported version (this lasercell reads version 1)",
           root["version"] ? root["version"] : root);
    }
    SphereTouches t;
    if (root["robot"]) t.robot = root["robot"].Scalar();
    if (root["frame"]) {
      t.frame = root["frame"].Scalar();
      if (t.frame != "handling_base") {
        Fail("frame '" + t.frame + "': touches must be given in handling_base", root["frame"]);
      }
    }
    if (root["stated_sigma_mm"]) {
      t.stated_sigma_mm = Number(root["stated_sigma_mm"], "stated_sigma_mm");
      if (!(t.stated_sigma_mm > 0)) Fail("stated_sigma_mm must be positive", root["stated_sigma_mm"]);
    }
    if (root["sphere_radius_mm"]) {
      const double r = Number(root["sphere_radius_mm"], "sphere_radius_mm");
      if (!(r > 0)) Fail("sphere_radius_mm must be positive", root["sphere_radius_mm"]);
      if (r < 1.0) {
        Fail("sphere_radius_mm " + root["sphere_radius_mm"].Scalar() +
                 " looks like metres; give millimetres", root["sphere_radius_mm"]);
      }
      t.sphere_radius_mm = r;
    }
    if (const YAML::Node tool = root["handling_flange_from_tool_tip"]) {
      if (!tool.IsMap()) Fail("handling_flange_from_tool_tip must be a pose mapping", tool);
      constexpr std::array<std::string_view, 2> kPose = {"translation_mm", "rotation_wxyz"};
      CheckFields(tool, kPose, "handling_flange_from_tool_tip");
      const auto tr = Numbers(tool["translation_mm"], "handling_flange_from_tool_tip.translation_mm");
      const auto q = Numbers(tool["rotation_wxyz"], "handling_flange_from_tool_tip.rotation_wxyz");
      if (tr.size() != 3 || q.size() != 4) {
        Fail("handling_flange_from_tool_tip needs translation_mm [x, y, z] and rotation_wxyz "
             "[w, x, y, z]", tool);
      }
      const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
      if (std::abs(quat.norm() - 1) > 1e-6) {
        Fail("handling_flange_from_tool_tip.rotation_wxyz is not a unit quaternion", tool);
      }
      t.handling_flange_from_tool_tip =
          PoseFromQuaternion(quat.normalized(), Eigen::Vector3d(tr[0], tr[1], tr[2]));
    }
    const YAML::Node list = root["touches"];
    if (!list || !list.IsSequence()) Fail("missing list 'touches'", root);
    std::set<int> labels;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YAML::Node e = list[i];
      const std::string where = "touches[" + std::to_string(i) + "]";
      if (!e.IsMap()) Fail(where + " must be a mapping", e);
      CheckFields(e, kTouch, where);
      SphereTouch touch;
      if (!e["sphere"]) Fail(where + ": missing 'sphere'", e);
      const double label = Number(e["sphere"], where + ".sphere");
      if (label != std::floor(label) || label < 0) {
        Fail(where + ".sphere must be a non-negative integer", e["sphere"]);
      }
      touch.sphere = static_cast<int>(label);
      if (!labels.insert(touch.sphere).second) {
        Fail(where + ": sphere " + std::to_string(touch.sphere) + " is touched twice", e);
      }
      if (!e["point_in_handling_base"]) Fail(where + ": missing 'point_in_handling_base'", e);
      const auto p = Numbers(e["point_in_handling_base"], where + ".point_in_handling_base");
      if (p.size() != 3) Fail(where + ".point_in_handling_base needs 3 numbers (mm)", e);
      touch.point_in_handling_base = Eigen::Vector3d(p[0], p[1], p[2]);
      if (e["joints_rad"] && !e["joints_rad"].IsNull()) {
        const auto q = Numbers(e["joints_rad"], where + ".joints_rad");
        for (double v : q) {
          if (std::abs(v) > 2 * std::numbers::pi + 1e-6) {
            Fail(where + ".joints_rad holds " + std::to_string(v) +
                     ", beyond +-2 pi: it looks like degrees; give radians",
                 e["joints_rad"]);
          }
        }
        touch.joints_rad = q;
      }
      t.touches.push_back(touch);
    }
    CheckUnits(t, list);
    return t;
  }

  // Mixed units: a point two orders of magnitude nearer the robot base than the others is in
  // metres among millimetres (a robot's reach is 100 mm to 3 m; its base origin is never touched).
  void CheckUnits(const SphereTouches& t, const YAML::Node& list) const {
    if (t.touches.empty()) return;
    double largest = 0;
    for (const auto& touch : t.touches) largest = std::max(largest, touch.point_in_handling_base.norm());
    for (std::size_t i = 0; i < t.touches.size(); ++i) {
      const double n = t.touches[i].point_in_handling_base.norm();
      if (largest > 50.0 && n < largest / 50.0) {
        Fail("touches[" + std::to_string(i) + "].point_in_handling_base is " +
                 std::to_string(n) + " from the base while another is " + std::to_string(largest) +
                 ": mixed units (metres among millimetres?); give every point in mm",
             list[i]);
      }
    }
    if (largest < 10.0) {
      Fail("every touch lies within 10 mm of the robot base: the points look like metres; "
           "give millimetres", list);
    }
  }

 private:
  std::string name_;
};

}  // namespace

SphereTouches ParseTouchesYaml(const std::string& text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FileError(name, std::string("not valid YAML: ") + e.what());
  }
  return TouchReader(name).Read(root);
}

}  // namespace lasercell::calib
