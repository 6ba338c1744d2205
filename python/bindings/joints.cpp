// The sphere-sweep calibrations of the vision robot from Python, as `lasercell calibrate joints`
// and `calibrate handeye-laser` run them (triangulation/sphere_sweeps.hpp): a list of sweeps of
// a sphere from many robot poses, triangulated through the cell's camera and laser plane, gives
// the robot's joint offsets (Skotheim's joint-offset step) or the laser sensor on the flange.
// Each result carries the updated cell (a FrameGraph) and its result document.
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>

#include "calib/joint_report.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"
#include "triangulation/sphere_sweeps.hpp"

namespace lasercell::python {
namespace {

using triangulation::JointCalibration;
using triangulation::LaserHandEyeCalibration;

// `spec` (the calibration's defaults) with the arguments filled in.
triangulation::SphereSweepProblemSpec Spec(triangulation::SphereSweepProblemSpec spec,
                                           const std::string& cell, const std::string& camera,
                                           const std::string& sweeps, const std::string& set,
                                           const std::string& robot, const std::string& touches,
                                           const py::object& laser_plane, const py::handle& up) {
  spec.cell = cell;
  spec.camera = camera;
  spec.sweeps = sweeps;
  if (!set.empty()) spec.set = set;
  spec.robot = robot;
  spec.touches = touches;
  if (!laser_plane.is_none()) {
    spec.laser_plane = ToVector4(laser_plane, "laser_plane");
  }
  spec.up = ToVector3(up, "up");
  return spec;
}

#define LASERCELL_SPEC_ARGS                                                            \
  py::arg("cell"), py::arg("camera"), py::arg("sweeps"),                               \
      py::arg("set") = "", py::arg("robot") = "vision_robot", py::arg("touches") = "", \
      py::arg("laser_plane") = py::none(), py::arg("up") = std::vector<double> {       \
    0.0, 0.0, 1.0                                                                      \
  }

}  // namespace

void BindJoints(py::module_& m) {
  py::class_<JointCalibration, std::shared_ptr<JointCalibration>>(
      m, "JointsResult", "The vision robot's identified joint offsets and the updated cell.")
      .def_property_readonly(
          "offsets",
          [](const JointCalibration& c) {
            py::dict out;
            for (std::size_t i = 0; i < c.result.parameter_names.size(); ++i) {
              if (!c.result.parameter_estimated[i]) continue;
              out[py::str(c.result.parameter_names[i])] =
                  py::make_tuple(c.result.parameter_corrections[i], c.result.parameter_sigmas[i]);
            }
            return out;
          },
          "{parameter: (identified - nominal, 1 sigma)} of the estimated parameters (rad, mm).")
      .def_property_readonly(
          "rms_mm", [](const JointCalibration& c) { return c.result.rms_mm; },
          LC_DOC(calib_JointIdentificationResult_rms_mm))
      .def_property_readonly(
          "converged", [](const JointCalibration& c) { return c.result.converged; },
          LC_DOC(calib_JointIdentificationResult_converged))
      .def_property_readonly(
          "warnings", [](const JointCalibration& c) { return c.result.warnings; },
          LC_DOC(calib_JointIdentificationResult_warnings))
      .def_readonly("cell", &JointCalibration::cell, LC_DOC(triangulation_JointCalibration_cell))
      .def(
          "summary", [](const JointCalibration& c) { return c.result.Summary(); },
          LC_DOC(calib_JointIdentificationResult_Summary))
      .def(
          "to_dict",
          [](const JointCalibration& c) {
            return JsonToPython(calib::JointCalibrationJson(c.result, c.run));
          },
          "The document `calibrate joints --json` writes.");

  py::class_<LaserHandEyeCalibration, std::shared_ptr<LaserHandEyeCalibration>>(
      m, "LaserHandEyeResult", "The laser sensor on the flange from sphere sweeps.")
      .def_property_readonly(
          "flange_from_sensor",
          [](const LaserHandEyeCalibration& c) {
            return FromIsometry(c.result.flange_from_sensor);
          },
          "4x4, mm.")
      .def_property_readonly(
          "covariance",
          [](const LaserHandEyeCalibration& c) { return FromMatrix(c.result.covariance); },
          LC_DOC(calib_LaserHandEyeResult_covariance))
      .def_property_readonly(
          "rms_mm", [](const LaserHandEyeCalibration& c) { return c.result.rms_mm; },
          LC_DOC(calib_LaserHandEyeResult_rms_mm))
      .def_readonly("cell", &LaserHandEyeCalibration::cell, "The cell with the new edge.")
      .def(
          "summary", [](const LaserHandEyeCalibration& c) { return c.result.Summary(); },
          LC_DOC(calib_LaserHandEyeResult_Summary))
      .def(
          "to_dict",
          [](const LaserHandEyeCalibration& c) {
            return JsonToPython(calib::LaserHandEyeJson(c.result, c.run));
          },
          "The document `calibrate handeye-laser --json` writes.");

  m.def(
      "calibrate_joints",
      [](const std::string& cell, const std::string& camera, const std::string& sweeps,
         const std::string& set, const std::string& robot, const std::string& touches,
         const py::object& laser_plane, const py::handle& up, bool with_handeye, bool dh_deltas) {
        const auto spec = Spec({}, cell, camera, sweeps, set, robot, touches, laser_plane, up);
        py::gil_scoped_release release;
        return std::make_shared<JointCalibration>(
            triangulation::CalibrateJointsFromSweeps(spec, with_handeye, dh_deltas));
      },
      LASERCELL_SPEC_ARGS, py::arg("with_handeye") = false, py::arg("dh_deltas") = false,
      R"doc(Joint offsets of the robot from sphere sweeps at many poses, as `calibrate joints`.

cell: cell.yaml with the robot and its flange -> sensor edge; sweeps: the sweep list
(records/sphere_sweeps.yaml) and its set; touches: the sphere tops touched by the handling
robot (fixes the centres); laser_plane: (4,) instead of the cell's `laser` plane. set '':
'joint_poses'.
with_handeye also estimates the flange -> sensor edge; dh_deltas the DH lengths and twists.)doc");
  m.def(
      "calibrate_handeye_laser",
      [](const std::string& cell, const std::string& camera, const std::string& sweeps,
         const std::string& set, const std::string& robot, const std::string& touches,
         const py::object& laser_plane, const py::handle& up) {
        const auto spec = Spec(triangulation::LaserHandEyeSpecDefaults(), cell, camera, sweeps, set,
                               robot, touches, laser_plane, up);
        py::gil_scoped_release release;
        return std::make_shared<LaserHandEyeCalibration>(
            triangulation::CalibrateLaserHandEyeFromSweeps(spec));
      },
      LASERCELL_SPEC_ARGS,
      "The laser sensor on the flange from sphere sweeps, as `calibrate handeye-laser` (same "
      "arguments as calibrate_joints; set '': 'eye_in_hand', up to 5000 points per sweep).");
}

}  // namespace lasercell::python
