// The half-sphere sensor-to-robot calibration from Python, as `calibrate spheres --profiles`
// runs it (triangulation/half_sphere_profiles.hpp): the sphere sweep's profiles triangulated
// through the calibrated camera and the cell's laser plane, the half spheres found and matched
// to the pointing tool's touches, and the edge handling_base <- sensor with its covariance and
// its response to the plane's error modes, ready to be written into the cell; or, as
// `calibrate spheres --sweep`, from a cloud already in the sweep frame.
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>

#include "calib/half_sphere_calibration.hpp"
#include "calib/half_sphere_report.hpp"
#include "core/io/file_util.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"
#include "triangulation/half_sphere_profiles.hpp"
#include "triangulation/linear_sweep.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::python {
namespace {

// A run and the edge it gives (what the CLI writes to the cell and into its JSON).
struct SpheresCalibration {
  calib::HalfSphereSweepResult run;
  calib::HalfSphereInputNames names;
  StaticEdge edge;
};
using SpheresPtr = std::shared_ptr<SpheresCalibration>;

triangulation::SweepOptions Motion(const std::string& linear_record,
                                   const py::object& velocity_mm_s,
                                   std::optional<std::int64_t> t0_ns) {
  if (!linear_record.empty()) return triangulation::ReadLinearSweepRecord(linear_record).Options();
  if (velocity_mm_s.is_none()) {
    ThrowInput(
        "velocity_mm_s: give the linear sweep's velocity (sensor frame at t0, mm/s) or "
        "linear_record");
  }
  triangulation::SweepOptions sweep;
  sweep.motion = triangulation::SweepMotion::kLinear;
  sweep.velocity_mm_s = ToVector3(velocity_mm_s, "velocity_mm_s");
  if (t0_ns) sweep.t0_ns = *t0_ns;
  return sweep;
}

SpheresPtr Calibrate(const FrameGraph& cell, const calib::CameraModel* camera,
                     const triangulation::ProfileSet* profiles, const std::string& touches_path,
                     const std::string& linear_record, const py::object& velocity_mm_s,
                     std::optional<std::int64_t> t0_ns, const std::string& laser,
                     const py::handle& up, double radius_mm, const PointCloud* cloud,
                     const std::string& sweep_frame) {
  if (touches_path.empty()) ThrowInput("touches: give the touches file (touches.yaml)");
  triangulation::SpheresSweep sweep;
  sweep.cloud = cloud;
  sweep.profiles = profiles;
  sweep.camera = camera;
  sweep.laser = laser;
  if (profiles) sweep.motion = Motion(linear_record, velocity_mm_s, t0_ns);
  calib::HalfSphereSweepOptions options;
  options.up_in_handling_base = ToVector3(up, "up");
  options.radius_mm = radius_mm;
  auto out = std::make_shared<SpheresCalibration>();
  out->names =
      calib::HalfSphereInputNames{"cell", cloud ? "cloud" : "profiles", touches_path, sweep_frame};
  py::gil_scoped_release release;
  triangulation::SpheresInCell run = triangulation::CalibrateSpheresInCell(
      cell, sweep, io::ReadFileBytes(touches_path), options, out->names);
  out->run = std::move(run.run);
  out->edge = std::move(run.edge);
  return out;
}

}  // namespace

void BindSpheres(py::module_& m) {
  py::class_<SpheresCalibration, SpheresPtr>(
      m, "SpheresResult", "The sensor placed in the handling-robot base by the half spheres.")
      .def_property_readonly(
          "handling_base_from_sensor",
          [](const SpheresCalibration& s) { return FromIsometry(s.edge.ParentFromChild()); },
          "4x4, mm: the sensor at the sphere sweep's t0.")
      .def_property_readonly(
          "covariance",
          [](const SpheresCalibration& s) { return FromMatrix(s.run.calibration.covariance); },
          "6x6 over [rotation vector (rad); translation (mm)], left perturbation.")
      .def_property_readonly(
          "sensor_modes_propagated",
          [](const SpheresCalibration& s) { return s.edge.sensor_response.has_value(); },
          "The edge carries its response to the laser plane's error modes.")
      .def_property_readonly(
          "warnings", [](const SpheresCalibration& s) { return s.run.calibration.warnings; },
          LC_DOC(calib_HalfSphereCalibrationResult_warnings))
      .def(
          "summary", [](const SpheresCalibration& s) { return s.run.calibration.Summary(); },
          LC_DOC(calib_HalfSphereCalibrationResult_Summary))
      .def(
          "to_dict",
          [](const SpheresCalibration& s) {
            return JsonToPython(calib::HalfSphereResultJson(s.run, s.names, s.edge));
          },
          "The document `calibrate spheres --json` writes.")
      .def(
          "set_in_cell",
          [](const SpheresCalibration& s, FrameGraph& cell) { cell.SetStaticEdge(s.edge); },
          py::arg("cell"), "Writes the edge handling_base <- sensor into cell (a FrameGraph).");

  m.def("calibrate_spheres", &Calibrate, py::arg("cell"), py::arg("camera") = nullptr,
        py::arg("profiles") = nullptr, py::arg("touches") = "", py::arg("linear_record") = "",
        py::arg("velocity_mm_s") = py::none(), py::arg("t0_ns") = py::none(),
        py::arg("laser") = "laser", py::arg("up") = std::vector<double>{0.0, 0.0, 1.0},
        py::arg("radius_mm") = 0.0, py::arg("cloud") = nullptr, py::arg("sweep_frame") = "sensor",
        R"doc(Sensor -> handling-robot base from half spheres (Skotheim et al. 2012, sec. III).

The sphere sweep is either profiles (a ProfileSet) triangulated through camera and the cell's
calibrated laser plane `laser` (a linear sweep given by linear_record, records/linear_sweep.yaml,
or by velocity_mm_s and t0_ns; the edge then keeps its response to the plane's error modes),
or cloud, a PointCloud already in sweep_frame (mm). touches: the pointing tool's touches file
(touches.yaml). As `calibrate spheres --profiles` / `--sweep`. InputError unless exactly one of
profiles and cloud is given; FileError naming the sweep when no sphere is found.)doc");
}

}  // namespace lasercell::python
