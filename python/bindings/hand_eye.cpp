// Eye-in-hand calibration from Python, as `lasercell calibrate handeye` runs it
// (calib/hand_eye_session.hpp): the camera on the vision robot's flange from chessboard images
// (or committed corner detections) and the robot's poses (kuka, yaml, xyzwpr, xyzabc files, or
// a joint record through the cell), ready to be written into the cell as the flange -> sensor
// edge with its covariance.
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "calib/hand_eye_session.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

using SessionPtr = std::shared_ptr<calib::HandEyeSession>;

SessionPtr Calibrate(const std::string& camera, const std::string& poses,
                     const std::vector<std::string>& images, const std::string& corners,
                     const std::string& board, const std::string& pose_format,
                     const std::string& method, const std::string& flange_frame,
                     const std::string& camera_frame, const std::string& robot,
                     const FrameGraph* cell, int threads, const py::object& progress) {
  calib::HandEyeInputs inputs;
  inputs.camera = camera;
  inputs.images = images;
  inputs.corners = corners;
  inputs.board = board;
  inputs.poses.path = poses;
  inputs.poses.format = pose_format;
  inputs.poses.flange_frame = flange_frame;
  inputs.poses.camera_frame = camera_frame;
  inputs.poses.robot = robot;
  inputs.method = method;
  inputs.threads = threads;
  inputs.tool = std::string("lasercell python ") + LASERCELL_VERSION;
  inputs.progress = ToProgress(progress);
  const FrameGraph empty;
  py::gil_scoped_release release;
  return std::make_shared<calib::HandEyeSession>(
      calib::CalibrateHandEyeFromFiles(inputs, cell != nullptr ? *cell : empty, "cell", nullptr));
}

}  // namespace

void BindHandEye(py::module_& m) {
  py::class_<calib::HandEyeSession, SessionPtr>(m, "HandEyeResult", LC_DOC(calib_HandEyeSession))
      .def_property_readonly(
          "flange_from_camera",
          [](const calib::HandEyeSession& s) { return FromIsometry(s.result.flange_from_camera); },
          "4x4, mm.")
      .def_property_readonly(
          "base_from_board",
          [](const calib::HandEyeSession& s) { return FromIsometry(s.result.base_from_board); },
          "4x4, mm: the fixed board in the robot base.")
      .def_property_readonly(
          "views", [](const calib::HandEyeSession& s) { return s.views.images; },
          "The images (or corner-file entries) used, in pose order.")
      .def_property_readonly(
          "warnings", [](const calib::HandEyeSession& s) { return s.result.warnings; },
          LC_DOC(calib_HandEyeResult_warnings))
      .def(
          "summary", [](const calib::HandEyeSession& s) { return s.result.Summary(); },
          LC_DOC(calib_HandEyeResult_Summary))
      .def(
          "to_dict",
          [](const calib::HandEyeSession& s) {
            return JsonToPython(calib::HandEyeJson(s.result, s.views, s.run));
          },
          "The document `calibrate handeye --json` writes.")
      .def(
          "set_in_cell",
          [](const calib::HandEyeSession& s, FrameGraph& cell) { cell.SetStaticEdge(s.edge); },
          py::arg("cell"), "Writes the flange -> camera edge (with covariance) into cell.");

  m.def("calibrate_handeye", &Calibrate, py::arg("camera"), py::arg("poses"),
        py::arg("images") = std::vector<std::string>{}, py::arg("corners") = "",
        py::arg("board") = "", py::arg("pose_format") = "auto", py::arg("method") = "park-martin",
        py::arg("flange_frame") = "vision_flange", py::arg("camera_frame") = "sensor",
        py::arg("robot") = "", py::arg("cell") = nullptr, py::arg("threads") = 1,
        py::arg("progress") = py::none(),
        R"doc(Eye-in-hand: the camera on the robot flange from views of a fixed chessboard.

camera: .cameramodel path; poses: the robot's base_from_flange per view (pose_format auto, kuka
(4x4, metres), yaml (mm), xyzwpr (Fanuc, deg), xyzabc (KUKA, deg) or record: joints through
cell); images in pose order with board ('chessboard:COLSxROWS:SQUARE_MM'), or corners (a
corners file). method: the closed form that starts the refinement (tsai-lenz, park-martin,
daniilidis). progress(stage, fraction): "detect" after each image, "solve" at the end; raising
in it stops the call. As `calibrate handeye`; the same errors, naming the file.)doc");
}

}  // namespace lasercell::python
