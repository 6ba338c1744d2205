#pragma once
// Robot pose files for hand-eye calibration: base_from_flange per image, in mm.
//
// Formats:
//  - kuka: the RWHE-Calib / kuka2 text form (Ali et al. 2019): one line per image, 16 numbers
//    (whitespace or commas), the row-major 4x4 homogeneous base->TCP transform, translation in
//    METRES (converted to mm here). Blank lines and lines starting with '#' are skipped.
//  - yaml: lasercell's form (mm):
//      format: lasercell.robot_poses
//      version: 1
//      # base_from_flange of each image, in image order
//      poses:
//        - {image: im_01.png, translation_mm: [x, y, z], rotation_wxyz: [w, x, y, z]}
//    (`image` optional). The simulator's records/hand_eye_images.yaml (format
//    lasercell.hand_eye_images) holds joints instead; ParseHandEyeImagesRecord reads those and
//    the caller turns them into poses through the cell's kinematic model.
//  - xyzwpr (Fanuc) and xyzabc (KUKA): base_from_flange as x y z in mm and three Euler angles
//    in DEGREES. Fanuc x y z w p r: R = Rz(r) * Ry(p) * Rx(w); KUKA x y z A B C: R = Rz(A) *
//    Ry(B) * Rx(C) (the same fixed-axis product, the angles in the opposite order on the line).
//    Two layouts, told apart by the first non-blank character:
//      text: one pose per line, 6 numbers separated by whitespace or commas; blank lines and
//            lines starting with '#' are skipped;
//      JSON ('{' first, RobCalibrator's .rob file): {"RobPoses": [[x, y, z, w, p, r], ...]},
//            no other key, every row exactly 6 numbers.
//    Such a file does not say which controller wrote it, so "auto" refuses it: pass xyzwpr or
//    xyzabc. An angle beyond +-360 is rejected (not degrees: swapped columns or another unit).
//
// Every reader checks: rotations orthonormal (|R^T R - I| <= 1e-6 for kuka; for yaml |q| within
// kUnitQuaternionTolerance of 1, core/se3.hpp, the one tolerance of every lasercell file; the
// rotation is then re-orthonormalised), translations in mm (all |t| < 5 looks like metres; a mix
// of |t| < 5 and |t| > 50 looks like mixed units), and throws FileError naming the file, the
// line and the problem. The YAML forms are read through yaml::Fields (core/yaml_fields.hpp):
// unknown fields are errors naming the line and the field path (`poses[2].rotation_wxyz`).

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "calib/board.hpp"

namespace lasercell::calib {

/// Robot poses, one per image.
struct RobotPoses {
  std::vector<Eigen::Isometry3d> base_from_flange;  ///< mm.
  std::vector<std::string> images;  ///< Image names when the file gives them, else empty.
};

/// Parses the kuka form (metres); `name` appears in errors.
RobotPoses ParseKukaPoses(const std::string& text, const std::string& name);
/// Parses the lasercell YAML form (mm); `name` appears in errors.
RobotPoses ParseYamlPoses(const std::string& text, const std::string& name);

/// Euler-angle conventions of robot controllers for x y z (mm) + three angles (degrees).
enum class EulerConvention {
  kFanucXyzwpr,  ///< Fanuc x y z w p r: R = Rz(r) * Ry(p) * Rx(w).
  kKukaXyzabc,   ///< KUKA x y z A B C: R = Rz(A) * Ry(B) * Rx(C).
};
/// The convention's name for messages: the format string, the controller, units and product,
/// e.g. "xyzwpr (Fanuc: x y z mm, w p r degrees, R = Rz(r) Ry(p) Rx(w))".
std::string EulerConventionName(EulerConvention convention);
/// Parses x y z + Euler-angle poses (mm, degrees), either layout (text lines or RobPoses JSON,
/// see the file comment), as base_from_flange; throws FileError(name, ...) naming the line
/// (text) or the pose (JSON) for a pose without exactly 6 finite numbers, an angle beyond
/// +-360 degrees, no poses, or translations that are not mm (CheckPoseUnits).
RobotPoses ParseEulerPoses(const std::string& text, const std::string& name,
                           EulerConvention convention);

/// records/hand_eye_images.yaml of the simulator: robot name, board and per-image joints.
struct HandEyeImagesRecord {
  std::string robot;                            ///< e.g. "vision_robot".
  BoardSpec board;                              ///< The chessboard (inner corners, square_mm).
  std::vector<std::string> images;              ///< Relative file names.
  std::vector<std::vector<double>> joints_rad;  ///< Per image.
};
/// Parses records/hand_eye_images.yaml (format lasercell.hand_eye_images, version 1, as
/// datasets::HandEyeImagesRecordYaml writes it: robot, board {squares, inner_corners,
/// square_mm}, images [{file, joints_rad}]); strict like the other readers; `name` appears in
/// errors.
HandEyeImagesRecord ParseHandEyeImagesRecord(const std::string& text, const std::string& name);

/// The lasercell YAML text of poses (round-trips through ParseYamlPoses).
std::string RobotPosesYaml(const RobotPoses& poses);

/// Checks units of poses in mm: throws FileError(name, ...) when every translation is below
/// 5 mm ("looks like metres") or when some are below 5 mm and others above 50 mm ("mixed units").
void CheckPoseUnits(const std::vector<Eigen::Isometry3d>& base_from_flange,
                    const std::string& name);

/// Chessboard corner detections of several images (the committed form of real data sets, and
/// `calibrate handeye --corners`). Text: a `# lasercell-chessboard-corners v1` first line, then
/// `board COLS ROWS SQUARE_MM` (inner corners), `image_size WIDTH HEIGHT`, and one line per
/// corner `IMAGE_NAME CORNER_INDEX U_PX V_PX` (corner index in OpenCV order, row by row along x;
/// pixel (0, 0) = centre of the top-left pixel). '#' lines are comments. Images keep file order.
struct ChessboardDetections {
  /// The chessboard these corners belong to (inner corners, square_mm; corner ids and
  /// board-frame positions as board.hpp).
  BoardSpec board;
  int width_px = 0, height_px = 0;                       ///< Image size.
  std::vector<std::string> images;                       ///< Image names, in order.
  std::vector<std::vector<Eigen::Vector2d>> corners_px;  ///< Per image, board.NumCorners().
};
/// Parses the text above; throws FileError(name, ...) naming the line.
ChessboardDetections ParseChessboardDetections(const std::string& text, const std::string& name);
/// Writes the text above (pixels with 4 decimals).
std::string ChessboardDetectionsText(const ChessboardDetections& detections,
                                     const std::string& comment = "");

/// Reads a pose file; format "kuka", "yaml", "xyzwpr", "xyzabc" or "auto" (yaml when the text
/// has a `format:` key, else kuka; a RobPoses JSON or lines of 6 numbers throw FileError asking
/// for xyzwpr or xyzabc, since the file does not say which). Other formats throw OptionError.
RobotPoses LoadRobotPoses(const std::string& path, const std::string& format = "auto");
/// LoadRobotPoses on text already read; `path` appears in errors.
RobotPoses ParseRobotPoses(const std::string& text, const std::string& path,
                           const std::string& format = "auto");

}  // namespace lasercell::calib
