// The laser eye-in-hand from one calibrated profile per robot pose across a fixed sphere
// (calib/sphere_section_hand_eye.hpp), with the files other software writes for it
// (triangulation/foreign_profiles.hpp: scan_line profiles; calib/pose_io.hpp: robot poses in a
// stated Euler convention): lasercell.read_scan_line_profile, read_robot_poses and
// calibrate_handeye_sections, the Python side of `calibrate handeye-laser --profiles`.
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "calib/pose_io.hpp"
#include "calib/sphere_section_hand_eye.hpp"
#include "calib/sphere_section_report.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"
#include "triangulation/foreign_profiles.hpp"

namespace lasercell::python {
namespace {

// One run: what was asked (for the result document) and what it gave.
struct SectionsCalibration {
  calib::SphereSectionRun run;
  calib::SphereSectionHandEyeResult result;
};
using SectionsPtr = std::shared_ptr<SectionsCalibration>;

int Side(const std::string& side) {
  if (side == "+y") return 1;
  if (side == "-y") return -1;
  ThrowInput(
      "sphere_side: expected '+y' or '-y' (the side of the laser plane the sphere centre "
      "lies on, sensor frame), got '" +
      side + "'");
}

// Sections from files (profiles: paths, poses: a pose file) or from arrays (profiles: (N, 3)
// arrays in the sensor frame, poses: 4x4 base_from_flange per profile).
std::vector<calib::SphereSectionProfile> Sections(const py::list& profiles, const py::object& poses,
                                                  const std::string& pose_format,
                                                  calib::SphereSectionRun* run) {
  if (profiles.empty()) ThrowInput("profiles: give one profile per robot pose");
  if (py::isinstance<py::str>(profiles[0])) {
    if (!py::isinstance<py::str>(poses)) {
      throw py::type_error("poses: with profile files give the pose file's path");
    }
    if (pose_format.empty()) {
      ThrowInput(
          "pose_format: required with a pose file (xyzwpr, xyzabc, kuka or yaml): Euler "
          "angles do not say their convention");
    }
    run->profile_paths = profiles.cast<std::vector<std::string>>();
    run->poses_path = poses.cast<std::string>();
    run->pose_format = pose_format;
    return triangulation::LoadSphereSections(run->profile_paths, run->poses_path, pose_format);
  }
  const py::sequence pose_list = poses.cast<py::sequence>();
  if (pose_list.size() != profiles.size()) {
    ThrowInput("poses: " + std::to_string(pose_list.size()) + " poses for " +
               std::to_string(profiles.size()) + " profiles; give one 4x4 per profile");
  }
  std::vector<calib::SphereSectionProfile> sections;
  for (std::size_t i = 0; i < profiles.size(); ++i) {
    const std::string name = "profiles[" + std::to_string(i) + "]";
    sections.push_back({name, ToIsometry(pose_list[i], "poses[" + std::to_string(i) + "]"),
                        ToVector3Rows(profiles[i], name)});
    run->profile_paths.push_back(name);
  }
  return sections;
}

SectionsPtr Calibrate(const py::list& profiles, const py::object& poses, double sphere_radius_mm,
                      const std::string& sphere_side, const std::string& pose_format,
                      bool estimate_radius, bool leave_one_out) {
  auto out = std::make_shared<SectionsCalibration>();
  calib::SphereSectionHandEyeOptions& o = out->run.options;
  o.sphere_radius_mm = sphere_radius_mm;
  o.sphere_side = Side(sphere_side);
  o.estimate_radius = estimate_radius;
  o.leave_one_out = leave_one_out;
  o.Check();
  const std::vector<calib::SphereSectionProfile> sections =
      Sections(profiles, poses, pose_format, &out->run);
  py::gil_scoped_release release;
  out->result = calib::CalibrateHandEyeFromSphereSections(sections, o);
  return out;
}

void BindResult(py::module_& m) {
  using R = calib::SphereSectionHandEyeResult;
  auto get = [](auto member) {
    return [member](const SectionsCalibration& c) { return c.result.*member; };
  };
  py::class_<SectionsCalibration, SectionsPtr>(
      m, "SphereSectionsResult", "The laser sensor on the flange from sphere sections.")
      .def_property_readonly(
          "flange_from_sensor",
          [](const SectionsCalibration& c) { return FromIsometry(c.result.flange_from_sensor); },
          "4x4, mm.")
      .def_property_readonly(
          "covariance",
          [](const SectionsCalibration& c) { return FromMatrix(c.result.covariance); },
          "6x6 over [rotation vector (rad); translation (mm)], left perturbation.")
      .def_property_readonly(
          "sphere_centre_in_base",
          [](const SectionsCalibration& c) {
            return py::array_t<double>(3, c.result.sphere_centre_in_base.data());
          },
          "(3,) mm.")
      .def_property_readonly("radius_mm", get(&R::radius_mm),
                             LC_DOC(calib_SphereSectionHandEyeResult_radius_mm))
      .def_property_readonly("sections_used", get(&R::sections_used),
                             LC_DOC(calib_SphereSectionHandEyeResult_sections_used))
      .def_property_readonly("spread_rms_mm", get(&R::spread_rms_mm),
                             LC_DOC(calib_SphereSectionHandEyeResult_spread_rms_mm))
      .def_property_readonly("spread_max_mm", get(&R::spread_max_mm),
                             LC_DOC(calib_SphereSectionHandEyeResult_spread_max_mm))
      .def_property_readonly("loo_rms_mm", get(&R::loo_rms_mm),
                             LC_DOC(calib_SphereSectionHandEyeResult_loo_rms_mm))
      .def_property_readonly("loo_max_mm", get(&R::loo_max_mm),
                             LC_DOC(calib_SphereSectionHandEyeResult_loo_max_mm))
      .def_property_readonly("rotation_span_deg", get(&R::rotation_span_deg),
                             LC_DOC(calib_SphereSectionHandEyeResult_rotation_span_deg))
      .def_property_readonly("converged", get(&R::converged),
                             LC_DOC(calib_SphereSectionHandEyeResult_converged))
      .def_property_readonly("warnings", get(&R::warnings),
                             LC_DOC(calib_SphereSectionHandEyeResult_warnings))
      .def(
          "summary", [](const SectionsCalibration& c) { return c.result.Summary(); },
          LC_DOC(calib_SphereSectionHandEyeResult_Summary))
      .def(
          "to_dict",
          [](const SectionsCalibration& c) {
            return JsonToPython(calib::SphereSectionHandEyeJson(c.result, c.run));
          },
          "The document `calibrate handeye-laser --profiles --json` writes (one entry per "
          "profile: circle, centre, distances, leave-one-out).")
      .def(
          "set_in_cell",
          [](const SectionsCalibration& c, FrameGraph& cell, const std::string& robot,
             const std::string& sensor_frame) {
            cell.SetStaticEdge(
                calib::SphereSectionEdge(cell, "cell", robot, sensor_frame, c.result));
          },
          py::arg("cell"), py::arg("robot") = "vision_robot", py::arg("sensor_frame") = "sensor",
          "Writes the flange -> sensor edge (with covariance) of the robot into cell.");
}

}  // namespace

void BindSections(py::module_& m) {
  py::class_<triangulation::ScanLineProfile>(m, "ScanLineProfile",
                                             LC_DOC(triangulation_ScanLineProfile))
      .def_property_readonly(
          "points",
          [](const triangulation::ScanLineProfile& p) { return RowsArray(p.points_in_sensor); },
          "(N, 3) finite (x, 0, z) points, mm, sensor frame, in column order.")
      .def_readonly("columns", &triangulation::ScanLineProfile::columns,
                    LC_DOC(triangulation_ScanLineProfile_columns))
      .def_readonly("missing", &triangulation::ScanLineProfile::missing,
                    LC_DOC(triangulation_ScanLineProfile_missing));
  m.def("read_scan_line_profile", &triangulation::ReadScanLineProfile, py::arg("path"),
        LC_DOC(triangulation_ReadScanLineProfile));
  m.def(
      "read_robot_poses",
      [](const std::string& path, const std::string& format) {
        const calib::RobotPoses poses = calib::LoadRobotPoses(path, format);
        py::list out;
        for (const Eigen::Isometry3d& pose : poses.base_from_flange) out.append(FromIsometry(pose));
        return out;
      },
      py::arg("path"), py::arg("format") = "auto",
      "base_from_flange per pose (4x4, mm) from a pose file: kuka (4x4, metres), yaml (mm), "
      "xyzwpr (Fanuc, R = Rz(r) Ry(p) Rx(w), deg) or xyzabc (KUKA, R = Rz(A) Ry(B) Rx(C), "
      "deg); 'auto' refuses Euler files, which do not say their convention.");
  BindResult(m);
  m.def("calibrate_handeye_sections", &Calibrate, py::arg("profiles"), py::arg("poses"),
        py::arg("sphere_radius_mm"), py::arg("sphere_side"), py::arg("pose_format") = "",
        py::arg("estimate_radius") = false, py::arg("leave_one_out") = true,
        LC_DOC(calib_CalibrateHandEyeFromSphereSections) R"doc(

In Python, as `calibrate handeye-laser --profiles`: profiles: scan_line file paths with poses a pose file (pose_format xyzwpr, xyzabc, kuka or
yaml), or (N, 3) arrays of points in the sensor's laser plane (y = 0, mm) with poses a list
of 4x4 base_from_flange (mm). sphere_side: '+y' or '-y', the side of the laser plane the sphere
centre lies on (one profile cannot tell). InputError names the profile or pose at fault, and
fewer than 5 usable sections or poses that do not turn about two axes.)doc");
}

}  // namespace lasercell::python
