#include "triangulation/half_sphere_profiles.hpp"

#include "core/error.hpp"
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

}  // namespace lasercell::triangulation
