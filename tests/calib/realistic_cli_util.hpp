#pragma once
// Test helper (not library code) of the realistic-profile chain tests: a realistic capture set
// with only the captures a test asks for, and the camera and laser-plane calibrations run by
// the CLI on it, as a user runs them (never given the truth).

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>

#include "calib/laser_plane_heights_record.hpp"
#include "core/frame_graph.hpp"
#include "datasets/sim_profile.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::test {

/// The realistic simulation profile with seed `seed` and every capture off: a test turns on
/// what it uses.
inline datasets::SimConfig RealisticConfigWithoutCaptures(std::uint64_t seed) {
  datasets::SimConfig config = datasets::SimConfigForProfile(datasets::SimProfile::kRealistic);
  config.seed = seed;
  config.capture_planes = config.capture_spheres = config.capture_seats = false;
  config.capture_trajectory = config.capture_chessboard_images = false;
  config.capture_laser_line_images = config.write_meshes = config.capture_touches = false;
  config.capture_eye_in_hand = config.capture_joint_poses = false;
  config.capture_hand_eye_images = false;
  return config;
}

/// "x,y,z" with every digit (a CLI vector argument).
inline std::string CsvOf(const Eigen::Vector3d& v) {
  return FormatDouble(v.x()) + "," + FormatDouble(v.y()) + "," + FormatDouble(v.z());
}

/// `calibrate camera` on the capture set's chessboard images (`sim`/images/chessboard_*.png,
/// the simulator's 9x6 board of 40 mm squares) -> `camera`, and `json` unless empty.
inline CommandResult CalibrateCameraByCli(const std::filesystem::path& sim,
                                          const std::filesystem::path& camera,
                                          const std::filesystem::path& json = {}) {
  return RunCliMerged("calibrate camera --images '" + (sim / "images").string() +
                      "/chessboard_*.png' --board chessboard:9x6:40 --out " + camera.string() +
                      (json.empty() ? std::string() : " --json " + json.string()));
}

/// `calibrate laser` from the capture set's plate sweeps (`sim`/profiles, the heights and plate
/// normal of `sim`/records/planes.yaml) through `camera`; the plane goes into `cell`, the result
/// into `json`.
inline CommandResult CalibrateLaserByCli(const std::filesystem::path& sim,
                                         const std::filesystem::path& camera,
                                         const std::filesystem::path& cell,
                                         const std::filesystem::path& json) {
  const calib::PlaneHeightsRecord planes =
      calib::ReadPlaneHeightsYaml((sim / "records/planes.yaml").string());
  std::string heights;
  for (double h : planes.heights_mm) {
    if (!heights.empty()) heights += ',';
    heights += FormatDouble(h);
  }
  return RunCliMerged("calibrate laser --camera " + camera.string() + " --planes " +
                      (sim / "profiles").string() + " --heights-mm " + heights +
                      " --plate-normal " + CsvOf(planes.plate_normal_in_sensor) + " --cell " +
                      cell.string() + " --json " + json.string());
}

}  // namespace lasercell::test
