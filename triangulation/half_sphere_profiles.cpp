#include "triangulation/half_sphere_profiles.hpp"

#include "core/error.hpp"
#include "core/provenance.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/sensor_error_field.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::triangulation {

HalfSphereFromProfiles CalibrateHalfSpheresFromProfiles(
    const FrameGraph& cell, const std::string& cell_name, const calib::CameraModel& camera,
    const ProfileSet& profiles, const SweepOptions& sweep, const std::string& laser,
    const calib::SphereTouches& touches, calib::HalfSphereSweepOptions options,
    const calib::HalfSphereInputNames& names) {
  LaserPlaneSource source;
  source.laser = laser;
  const ScanSetup setup = ScanSetupFromCell(&cell, cell_name, source, sweep);
  HalfSphereFromProfiles out;
  out.sweep =
      AssembleSweep(profiles, Triangulator(camera, setup.laser_plane), setup.options, &cell);
  const LaserPlaneEntry& plane = cell.laser_planes().at(laser);
  if (!plane.error_modes.empty()) {
    options.point_displacements = CloudPointDisplacements(
        SensorErrorField(camera, plane), out.sweep.cloud, out.sweep.frame_from_sensor);
    out.modes_propagated = true;
  }
  out.run = calib::CalibrateHalfSpheresInSweep(out.sweep.cloud, touches, options, names);
  return out;
}

std::optional<SensorModeResponse> SensorResponseOf(const calib::HalfSphereSweepResult& run,
                                                   const FrameGraph& cell,
                                                   const std::string& laser) {
  if (run.mode_response.cols() == 0) return std::nullopt;
  return SensorModeResponse{laser, cell.laser_planes().at(laser).provenance.input_digest,
                            run.mode_response};
}

StaticEdge HalfSphereCellEdge(const calib::HalfSphereSweepResult& run, const FrameGraph& cell,
                              const std::string& laser, const calib::HalfSphereInputNames& names,
                              const std::string& input_digest) {
  if (!run.calibrated) throw FileError(names.sweep, run.failure);
  StaticEdge edge =
      calib::HalfSphereEdge(run.calibration, names.sweep_frame,
                            calib::HalfSphereProvenance(run.calibration, input_digest));
  edge.sensor_response = SensorResponseOf(run, cell, laser);
  return edge;
}

SpheresInCell CalibrateSpheresInCell(const FrameGraph& cell, const SpheresSweep& sweep,
                                     const std::string& touches_text,
                                     const calib::HalfSphereSweepOptions& options,
                                     const calib::HalfSphereInputNames& names) {
  if ((sweep.cloud == nullptr) == (sweep.profiles == nullptr)) {
    throw InputError("calibrate spheres: give the sweep as a cloud or as profiles (one of them)");
  }
  if (sweep.profiles && !sweep.camera) {
    throw InputError("calibrate spheres: profiles need the camera model that triangulates them");
  }
  calib::CheckHalfSphereEdgeFits(cell, names.sweep_frame, names.cell);
  const calib::SphereTouches touches = calib::ParseTouchesYaml(touches_text, names.touches);
  SpheresInCell out;
  InputDigest digest;
  if (sweep.profiles) {
    HalfSphereFromProfiles run =
        CalibrateHalfSpheresFromProfiles(cell, names.cell, *sweep.camera, *sweep.profiles,
                                         sweep.motion, sweep.laser, touches, options, names);
    out.run = std::move(run.run);
    out.modes_propagated = run.modes_propagated;
    if (sweep.file.empty()) digest.Add(EncodeProfiles(*sweep.profiles));
  } else {
    out.run = calib::CalibrateHalfSpheresInSweep(*sweep.cloud, touches, options, names);
    if (sweep.file.empty()) {
      const auto& p = sweep.cloud->positions;
      digest.Add(
          std::string(reinterpret_cast<const char*>(p.data()), p.size() * sizeof(Eigen::Vector3d)));
    }
  }
  if (!sweep.file.empty()) digest.AddFile(sweep.file);
  digest.Add(touches_text);
  out.edge = HalfSphereCellEdge(out.run, cell, sweep.laser, names, digest.Text());
  return out;
}

}  // namespace lasercell::triangulation
