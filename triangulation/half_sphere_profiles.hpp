#pragma once
// The half-sphere sensor-to-robot calibration (calib/half_sphere_calibration.hpp) started from
// the sphere sweep's profiles instead of a cloud: the sweep is triangulated here through the
// calibrated camera and the cell's laser plane, so the calibration also knows how each of that
// sensor's error modes (core/frame_graph.hpp SensorErrorMode) moved it. The edge keeps that
// response (StaticEdge::sensor_response) and a job measuring through the same camera and plane
// counts their shared error once, with its sign (localize/laser_plane_uncertainty.hpp), instead
// of twice or not at all.

#include <optional>
#include <string>

#include "calib/camera_model.hpp"
#include "calib/half_sphere_calibration.hpp"
#include "core/frame_graph.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/sweep.hpp"

namespace lasercell::triangulation {

/// What CalibrateHalfSpheresFromProfiles produced.
struct HalfSphereFromProfiles {
  SweepResult sweep;                 ///< The triangulated sphere sweep (sweep frame: "sensor").
  calib::HalfSphereSweepResult run;  ///< With mode_response when the plane has error modes.
  /// The plane's error modes were propagated (false: the plane has none; the edge then carries
  /// no sensor_response).
  bool modes_propagated = false;
};

/// Triangulates `profiles` through `camera` and the laser plane `laser` of `cell` with `sweep`
/// (ScanSetupFromCell's checks; `cell_name` names the cell in messages), then runs
/// CalibrateHalfSpheresInSweep with `options` (point_displacements set here when the plane has
/// error modes). Throws what those throw.
HalfSphereFromProfiles CalibrateHalfSpheresFromProfiles(
    const FrameGraph& cell, const std::string& cell_name, const calib::CameraModel& camera,
    const ProfileSet& profiles, const SweepOptions& sweep, const std::string& laser,
    const calib::SphereTouches& touches, calib::HalfSphereSweepOptions options,
    const calib::HalfSphereInputNames& names);

/// The edge's sensor_response for `run` (the plane `laser` of `cell`, its provenance digest);
/// nullopt when the run has no mode response.
std::optional<SensorModeResponse> SensorResponseOf(const calib::HalfSphereSweepResult& run,
                                                   const FrameGraph& cell,
                                                   const std::string& laser);

/// The cell's new edge handling_base <- names.sweep_frame from `run`: the calibrated pose and
/// covariance (calib::HalfSphereEdge), its provenance (calib::HalfSphereProvenance with
/// `input_digest`, the InputDigest of the sweep and the touches) and, when the run has one, the
/// response to the error modes of the plane `laser` of `cell` (SensorResponseOf). What
/// `calibrate spheres` writes to the cell. Throws FileError naming names.sweep with the run's
/// failure when it did not calibrate.
StaticEdge HalfSphereCellEdge(const calib::HalfSphereSweepResult& run, const FrameGraph& cell,
                              const std::string& laser, const calib::HalfSphereInputNames& names,
                              const std::string& input_digest);

/// The sphere sweep CalibrateSpheresInCell starts from: a cloud in the sweep frame, or the
/// profiles with the camera and the linear sweep that triangulate them through the cell's
/// laser plane (the edge then keeps its response to the plane's error modes).
struct SpheresSweep {
  const PointCloud* cloud = nullptr;     ///< In names.sweep_frame, mm; not owned.
  const ProfileSet* profiles = nullptr;  ///< Or these (not owned), with camera and motion.
  const calib::CameraModel* camera = nullptr;
  SweepOptions motion;
  std::string laser = "laser";  ///< The cell's laser plane.
  /// The file the sweep came from: the provenance digests its bytes ("" = the data: the
  /// encoded profiles or the cloud's positions).
  std::string file;
};

/// What CalibrateSpheresInCell produced: the run and the edge for the cell.
struct SpheresInCell {
  calib::HalfSphereSweepResult run;
  StaticEdge edge;
  bool modes_propagated = false;  ///< As HalfSphereFromProfiles (false for a cloud).
};

/// `calibrate spheres` between reading its inputs and writing the cell: checks that the edge
/// handling_base <- names.sweep_frame fits `cell` (names.cell names it), parses the touches
/// (`touches_text`, named names.touches), calibrates from the cloud or the profiles and builds
/// the edge (HalfSphereCellEdge) with the digest of the sweep and the touches. Throws
/// InputError when the sweep gives neither or both of cloud and profiles, or profiles without
/// a camera, and what those steps throw.
SpheresInCell CalibrateSpheresInCell(const FrameGraph& cell, const SpheresSweep& sweep,
                                     const std::string& touches_text,
                                     const calib::HalfSphereSweepOptions& options,
                                     const calib::HalfSphereInputNames& names);

}  // namespace lasercell::triangulation
