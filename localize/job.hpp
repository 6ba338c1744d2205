#pragma once
// The job file (YAML, format `lasercell.job`, version 1): one localization job of a cell. Paths
// are relative to the job file.
//
//   format: lasercell.job
//   version: 1
//   cell: cell.yaml                 # frame graph with the calibrated edges and laser plane
//   camera: camera.cameramodel      # mrcal camera model of the sensor
//   laser: laser                    # name of the laser plane in the cell (default laser)
//   source: {file: seat_000.lcp}    # where the profiles come from (a profile file today)
//   trajectory:                     # how profiles are placed: one of
//     linear: records/linear_sweep.yaml   # a linear axis (sensor velocity, t0), or
//     # robot: vision_robot               # robot joints in the profiles ("" = the file's robot)
//   target_frame: handling_base     # poses are reported in this frame (default handling_base)
//   roi: {min_mm: [x, y, z], max_mm: [x, y, z]}   # optional box in the target frame
//   support_plane: {normal: [0, 0, 1], offset_mm: 0, max_penetration_mm: 3}   # optional
//   parts:
//     - {part: seat.part.yaml, instances: 1}
//   grasp_tolerance_mm: 10          # a grasp is "graspable" when its 3-sigma position error is
//                                   # within this (the paper's gripper: +-10 mm)
//   scan_noise_mm: 0.1              # the sensor's 1-sigma range noise (plausibility of ICP)
//   max_rmse_factor: 5              # ICP RMSE above factor x noise -> not graspable
//   threads: 0                      # 0 = all cores
//   model_cache: .lasercell-cache   # optional folder for built PPF models
//   localize: {...}                 # optional localize options (registration's options file
//                                   # keys), or
//   # localize_options: options.yaml
//
// Every field but the optional ones is required; unknown fields are errors naming the file and
// the field (core/yaml_fields.hpp). Units mm.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "localize/part.hpp"
#include "registration/localize_options_io.hpp"

namespace lasercell::localize {

/// Format name and version of job files.
inline constexpr const char* kJobFormat = "lasercell.job";
inline constexpr int kJobFormatVersion = 1;

/// A part the job looks for.
struct JobPart {
  std::string file;     ///< The part file, resolved against the job file's folder.
  PartDefinition part;  ///< Its definition (read with the job).
  int instances = 1;    ///< Instances to find at most (>= 1).
};

/// A plane the parts rest on, in the target frame: {p : normal . p = offset_mm}, normal toward
/// free space. Poses tilted off the part's stable poses or sinking below it are rejected.
struct SupportPlane {
  bool enabled = false;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< Unit.
  double offset_mm = 0.0;
  double max_penetration_mm = 3.0;  ///< < 0: no sinking test.
};

/// Everything a job file says, paths resolved.
struct Job {
  std::string file;               ///< The job file ("" when built in memory).
  std::string cell;               ///< cell.yaml.
  std::string camera;             ///< .cameramodel.
  std::string laser = "laser";    ///< The laser plane's name in the cell.
  std::string profiles;           ///< source.file: a .lcp profile file.
  std::string linear_record;      ///< trajectory.linear ("" for a robot trajectory).
  bool robot_trajectory = false;  ///< trajectory.robot given.
  std::string robot;              ///< trajectory.robot ("" = the profile file's robot).
  std::string target_frame = "handling_base";  ///< Frame of the sweep and every pose.
  bool use_roi = false;
  BoundingBox roi;  ///< In the target frame, mm.
  SupportPlane support;
  std::vector<JobPart> parts;
  double grasp_tolerance_mm = 10.0;  ///< mm; graspable when 3 sigma of a grasp is within.
  double scan_noise_mm = 0.1;
  double max_rmse_factor = 5.0;
  int threads = 0;
  std::string model_cache;                  ///< "" = each part file's folder + "/.lasercell-cache".
  registration::LocalizeSettings settings;  ///< Localize options (defaults where silent).

  /// Throws InputError naming the file and field for values out of range (empty parts list, an
  /// empty ROI, a non-unit support normal, a tolerance <= 0, ...).
  void Check() const;
};

/// Parses job-file text; `path` names it in errors and resolves relative paths. Reads the part
/// files it names. Throws OptionError naming the file and field for unknown or missing fields,
/// FileError for a part file that cannot be read.
Job ParseJobFile(const std::string& text, const std::string& path);
/// Reads and parses a job file (FileError when it cannot be read).
Job ReadJobFile(const std::string& path);

}  // namespace lasercell::localize
