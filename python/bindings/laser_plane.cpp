// Laser plane calibration from Python (calib/laser_plane.hpp), both methods of
// `lasercell calibrate laser`: (a) a white plate swept at known heights (its plane_<i>.lcp
// profile files, triangulation/laser_plane_captures.hpp) and (b) a stripe across a chessboard
// of unknown pose (images). The result writes itself into a FrameGraph with its covariance and
// error modes, as the CLI writes the cell.
#include "calib/laser_plane.hpp"

#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "calib/camera_model.hpp"
#include "calib/laser_plane_report.hpp"
#include "core/provenance.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"
#include "triangulation/laser_plane_captures.hpp"

namespace lasercell::python {
namespace {

using calib::LaserPlaneResult;
using ResultPtr = std::shared_ptr<LaserPlaneResult>;

// A result and the digest of its inputs (the cell entry's provenance).
struct LaserPlaneCalibration {
  LaserPlaneResult result;
  std::string input_digest;
};
using CalibrationPtr = std::shared_ptr<LaserPlaneCalibration>;

CalibrationPtr FromHeights(const calib::CameraModel& camera, const std::string& planes,
                           const py::handle& heights_mm, const py::handle& plate_normal,
                           std::optional<double> plate_distance_mm, bool estimate_plate_tilt) {
  calib::HeightPlaneOptions options;
  options.plate_normal_in_sensor = ToVector3(plate_normal, "plate_normal");
  options.zero_distance_mm = plate_distance_mm;
  options.estimate_plate_tilt = estimate_plate_tilt;
  const std::vector<double> heights =
      ToDoubles(heights_mm, "heights_mm", static_cast<std::size_t>(-1));
  py::gil_scoped_release release;
  InputDigest digest;
  calib::LaserPlaneResult result =
      triangulation::CalibrateLaserPlaneFromPlaneFiles(camera, planes, heights, options, &digest);
  return std::make_shared<LaserPlaneCalibration>(
      LaserPlaneCalibration{std::move(result), digest.Text()});
}

CalibrationPtr FromStripes(const calib::CameraModel& camera,
                           const std::vector<std::string>& image_paths,
                           const calib::BoardSpec& board, const std::string& laser_color) {
  calib::StripeOptions options;
  options.laser_color = laser_color;
  py::gil_scoped_release release;
  InputDigest digest;
  calib::LaserPlaneResult result = triangulation::CalibrateLaserPlaneFromStripeFiles(
      camera, image_paths, board, options, &digest);
  return std::make_shared<LaserPlaneCalibration>(
      LaserPlaneCalibration{std::move(result), digest.Text()});
}

}  // namespace

void BindLaserPlane(py::module_& m) {
  py::class_<LaserPlaneCalibration, CalibrationPtr>(
      m, "LaserPlaneResult", "A laser plane n . p + d = 0 in the sensor frame, and its quality.")
      .def_property_readonly(
          "plane",
          [](const LaserPlaneCalibration& c) {
            const LaserPlaneResult& r = c.result;
            const double v[4] = {r.normal.x(), r.normal.y(), r.normal.z(), r.offset_mm};
            return py::array_t<double>(4, v);
          },
          "(4,) (n, d): unit normal and offset, mm (the laser_plane of scan_profiles).")
      .def_property_readonly(
          "covariance",
          [](const LaserPlaneCalibration& c) { return FromMatrix(c.result.covariance); },
          "4x4 over [n; d].")
      .def_property_readonly(
          "normal_sigma_deg",
          [](const LaserPlaneCalibration& c) { return c.result.normal_sigma_deg; },
          LC_DOC(calib_LaserPlaneResult_normal_sigma_deg))
      .def_property_readonly(
          "offset_sigma_mm",
          [](const LaserPlaneCalibration& c) { return c.result.offset_sigma_mm; },
          LC_DOC(calib_LaserPlaneResult_offset_sigma_mm))
      .def_property_readonly(
          "rms_mm", [](const LaserPlaneCalibration& c) { return c.result.rms_mm; },
          LC_DOC(calib_LaserPlaneResult_rms_mm))
      .def_property_readonly(
          "points", [](const LaserPlaneCalibration& c) { return c.result.points; },
          LC_DOC(calib_LaserPlaneResult_points))
      .def_property_readonly(
          "converged", [](const LaserPlaneCalibration& c) { return c.result.converged; },
          LC_DOC(calib_LaserPlaneResult_converged))
      .def_property_readonly(
          "warnings", [](const LaserPlaneCalibration& c) { return c.result.warnings; },
          LC_DOC(calib_LaserPlaneResult_warnings))
      .def(
          "summary", [](const LaserPlaneCalibration& c) { return c.result.Summary(); },
          LC_DOC(calib_LaserPlaneResult_Summary))
      .def(
          "refusal_reason", [](const LaserPlaneCalibration& c) { return c.result.RefusalReason(); },
          "Why this plane must not be written to a cell ('' when it may).")
      .def(
          "to_dict",
          [](const LaserPlaneCalibration& c, const std::string& camera) {
            return JsonToPython(calib::LaserPlaneJson(c.result, camera));
          },
          py::arg("camera") = "",
          "The document `calibrate laser --json` writes (camera: the model's path).")
      .def(
          "set_in_cell",
          [](const LaserPlaneCalibration& c, FrameGraph& cell, const std::string& name) {
            const std::string refusal = c.result.RefusalReason();
            if (!refusal.empty()) ThrowInput("laser plane not written to the cell: " + refusal);
            EdgeProvenance provenance;
            provenance.tool = std::string("lasercell python ") + LASERCELL_VERSION;
            provenance.date = UtcTimestampIso();
            provenance.input_digest = c.input_digest;
            cell.SetLaserPlane(name, calib::LaserPlaneCellEntry(c.result, provenance));
          },
          py::arg("cell"), py::arg("name") = "laser",
          "Writes the plane into cell (a FrameGraph) with its covariance and error modes, as "
          "`calibrate laser --cell` does; InputError when refusal_reason() is not empty.");

  m.def("calibrate_laser_plane_from_heights", &FromHeights, py::arg("camera"), py::arg("planes"),
        py::arg("heights_mm"), py::arg("plate_normal") = std::vector<double>{0.0, 0.0, -1.0},
        py::arg("plate_distance_mm") = py::none(), py::arg("estimate_plate_tilt") = true,
        R"doc(Method (a): the plate swept at known heights.

planes: the folder holding plane_<i>.lcp (or its profiles/ folder); heights_mm: one height per
file, along plate_normal (sensor frame); plate_distance_mm: the sensor-to-plate distance at
height 0 when known (needed with only 2 heights). As `calibrate laser --planes`.)doc");
  m.def("calibrate_laser_plane_from_stripes", &FromStripes, py::arg("camera"),
        py::arg("image_paths"), py::arg("board"), py::arg("laser_color") = "green",
        "Method (b): a laser stripe across a chessboard of unknown pose, in each image; as "
        "`calibrate laser --stripe-images`.");
}

}  // namespace lasercell::python
