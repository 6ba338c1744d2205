#pragma once
// The part definition file (YAML, format `lasercell.part`, version 1): what a job looks for.
//
//   format: lasercell.part
//   version: 1
//   name: seat                      # lower snake case; instance frames are <name>_<k>
//   model: seat.step                # CAD (.step/.stp/.iges/.igs) or mesh (.stl/.obj/.ply),
//                                   # relative to the part file
//   units: mm                       # meshes only (mm, cm, m, inch); CAD files carry their own
//   grasps:                         # named grasp frames in the part frame
//     hole:
//       part_from_grasp: {translation_mm: [x, y, z], rotation_wxyz: [w, x, y, z]}
//       description: gripper fingers into the 27 mm hole, approach along -z of the frame
//   stable_poses:                   # optional: part axes that point up when the part rests
//     up_in_part: [[0, 0, 1]]
//     max_tilt_deg: 30
//   symmetry: {kind: none}          # or {kind: axial, axis_in_part: [0,0,1]} (continuous), or
//                                   # {kind: discrete, axis_in_part: [...], order: N}
//   cad: {sampling_step_mm: 1.0, linear_deflection_mm: 0.05, angular_deflection_rad: 0.3}
//   model_options: {...}            # PpfModelOptions keys (registration/localize_options_io)
//
// Frames: the part frame is the CAD file's own (converted to mm); a grasp frame `g` is placed by
// part_from_grasp, so handling_base_from_g = handling_base_from_part * part_from_grasp is the
// target of the handling robot's gripper_tcp. Units: mm; the file gives tilts in degrees.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/se3.hpp"
#include "localize/cad_import.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::localize {

/// Format name and version of part files.
inline constexpr const char* kPartFormat = "lasercell.part";
inline constexpr int kPartFormatVersion = 1;

/// A named frame on the part the handling robot's gripper_tcp is sent to.
struct GraspFrame {
  std::string name;                ///< Lower snake case, unique within the part.
  QuaternionPose part_from_grasp;  ///< Kept as written.
  std::string description;         ///< Free text (may be empty).
  /// Radius around the grasp origin (part frame, mm) whose fit decides the grasp pose: after
  /// the part's ICP, ICP over only the model and scan points within it refines where the grasp
  /// is (a warped or flexed part fits best near the feature the gripper engages; the whole
  /// part's fit spreads its deformation over every point). 0 (default): the part's pose
  /// decides. Part file key `refine_radius_mm`.
  double refine_radius_mm = 0.0;
};

/// Symmetry of the part: a symmetric part's pose is undetermined about the axis.
struct PartSymmetry {
  enum class Kind { kNone, kAxial, kDiscrete };
  Kind kind = Kind::kNone;
  Eigen::Vector3d axis_in_part = Eigen::Vector3d::UnitZ();  ///< Unit axis through the origin.
  int order = 0;  ///< kDiscrete: poses repeat every 360/order degrees (>= 2).
};

/// How the real part departs from its model along the surface normal, as an inspection of the
/// part against its CAD reports it (a moulded or cast part warps; a mesh's facets cut chords).
/// The localizer does not correct it: it widens the pose covariance by it
/// (registration::IcpOptions::model_error_sigma_mm, file comment of registration/icp.hpp).
/// Part file key `form_deviation: {rms_mm, correlation_mm}`.
struct FormDeviation {
  /// RMS distance of the part's surface from the model, mm; 0 (default) = the model is exact.
  /// In [0, 100].
  double rms_mm = 0.0;
  /// Length over which the deviation keeps its sign, mm (about the size of one bump of the
  /// inspection's deviation map). In (0, 10000].
  double correlation_mm = 20.0;
};

/// Everything a part file says, with its model path resolved.
struct PartDefinition {
  std::string name;        ///< Lower snake case.
  std::string file;        ///< The part file itself ("" when built in memory).
  std::string model;       ///< The model path as written in the file.
  std::string model_path;  ///< Resolved against the part file's folder.
  std::string units;       ///< Mesh unit ("mm", "cm", "m", "inch"); "" for CAD (from the file).
  std::vector<GraspFrame> grasps;
  std::vector<Eigen::Vector3d> stable_up_in_part;  ///< Unit axes; empty = any orientation.
  double max_tilt_rad = 0.5235987755982988;        ///< Tilt allowed around a stable pose (30°).
  PartSymmetry symmetry;
  CadImportOptions cad;                         ///< Sampling and tessellation of CAD and meshes.
  registration::PpfModelOptions model_options;  ///< The PPF model's build options.
  FormDeviation form_deviation;                 ///< The part against its model.

  /// The grasp of this name; InputError naming the part and the known grasps when absent.
  const GraspFrame& Grasp(const std::string& grasp_name) const;
  /// Throws InputError naming `file` and the field for a bad name, duplicate grasp names, a
  /// non-unit stable axis or symmetry axis, a discrete order < 2, an unknown unit, a model with
  /// units given for CAD (the file's own rule) or missing for a mesh, a form deviation out of
  /// range, and bad options.
  void Check() const;
};

/// Scale from a unit name to mm ("mm" 1, "cm" 10, "m" 1000, "inch"/"in" 25.4); OptionError
/// naming `field` otherwise.
double UnitToMm(const std::string& unit, const std::string& field);
/// True for .step/.stp/.iges/.igs (case-insensitive).
bool IsCadFile(const std::string& path);

/// Parses part-file text; `path` names it in errors and resolves `model`. Throws OptionError
/// ("<file>: line N: field '<path>' ...") for unknown or missing fields, a wrong format/version
/// or bad values (PartDefinition::Check).
PartDefinition ParsePartFile(const std::string& text, const std::string& path);
/// Reads and parses a part file (FileError when it cannot be read).
PartDefinition ReadPartFile(const std::string& path);
/// The file text of a definition (model as written); parses back to the same definition.
std::string PartFileYaml(const PartDefinition& part);
/// Writes PartFileYaml atomically.
void WritePartFile(const std::string& path, const PartDefinition& part);

}  // namespace lasercell::localize
