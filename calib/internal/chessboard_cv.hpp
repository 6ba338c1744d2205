#pragma once
// OpenCV helpers of the hand-eye calibration (private to calib/ and the bench): chessboard corner
// detection (findChessboardCornersSB + cornerSubPix) until calib/target_detection lands, and PnP
// on normalised image coordinates. Units: mm for board points, px for pixels.

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lasercell::calib::internal {

/// Inner corners of a chessboard with `cols` x `rows` inner corners and `square_mm` squares, in
/// OpenCV's order (row by row along x), board frame (z = 0), mm.
std::vector<Eigen::Vector3d> ChessboardCorners(int cols, int rows, double square_mm);

/// Detects the cols x rows inner corners in an 8-bit gray image (row-major, width x height):
/// findChessboardCornersSB (CALIB_CB_ACCURACY, then exhaustive), then cornerSubPix (5 x 5 half
/// window). Returns nullopt when no board of that size is found. NOTE: the SB detector also finds
/// a smaller sub-board of a larger printed board: give the true inner-corner count. Pixel (0, 0) is the centre of the top-left pixel.
std::optional<std::vector<Eigen::Vector2d>> DetectChessboardCorners(
    const std::vector<std::uint8_t>& gray, int width, int height, int cols, int rows);

/// Reads an image file as 8-bit gray and detects the corners (as above); `width`/`height` get
/// the image size. Throws FileError when the image cannot be read.
std::optional<std::vector<Eigen::Vector2d>> DetectChessboardCornersInFile(
    const std::string& path, int cols, int rows, int* width, int* height);

/// camera_from_board from board points and their normalised image coordinates (x/z, y/z):
/// OpenCV solvePnP (iterative) with K = I and no distortion.
Eigen::Isometry3d SolvePnPNormalised(const std::vector<Eigen::Vector3d>& p_in_board,
                                     const std::vector<Eigen::Vector2d>& normalised);

}  // namespace lasercell::calib::internal
