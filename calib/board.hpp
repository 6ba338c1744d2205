#pragma once
// Calibration targets: planar boards whose inner corners are the observed features.
//
// Board frame: the pattern lies in the board's xy plane (z = 0); corner ids run row by row
// (x fastest), as OpenCV orders them. Units mm.
//  - chessboard:COLSxROWS:SQUARE_MM   COLS x ROWS inner corners (OpenCV's patternSize), corner
//    (c, r) at (c * SQUARE_MM, r * SQUARE_MM, 0), id r * COLS + c.
//  - charuco:SXxSY:SQUARE_MM:MARKER_MM[:DICT]   SX x SY squares (OpenCV's CharucoBoard::create
//    squaresX, squaresY), ArUco markers MARKER_MM wide from dictionary DICT (default
//    DICT_4X4_50; any cv::aruco::PREDEFINED_DICTIONARY_NAME such as DICT_5X5_100). Inner corner
//    (c, r), c < SX - 1, r < SY - 1, at ((c + 1) * SQUARE_MM, (r + 1) * SQUARE_MM, 0), id
//    r * (SX - 1) + c: OpenCV 4.6's charuco corner ids and positions.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace lasercell::calib {

enum class BoardType { kChessboard, kCharuco };

/// A calibration board. Build with ParseBoardSpec or fill and Check().
struct BoardSpec {
  BoardType type = BoardType::kChessboard;
  int cols = 9;             ///< Chessboard: inner corners per row; ChArUco: squares along x.
  int rows = 6;             ///< Chessboard: inner corners per column; ChArUco: squares along y.
  double square_mm = 25.0;  ///< Square edge, mm.
  double marker_mm = 0.0;   ///< ChArUco marker edge, mm (< square_mm); unused for chessboards.
  std::string dictionary = "DICT_4X4_50";  ///< ChArUco ArUco dictionary name.

  /// A chessboard with `cols` x `rows` inner corners and `square_mm` squares.
  static BoardSpec Chessboard(int cols, int rows, double square_mm);

  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
  /// Inner corners per row / column (chessboard: cols/rows; ChArUco: squares - 1).
  int CornersX() const;
  int CornersY() const;
  int NumCorners() const { return CornersX() * CornersY(); }  ///< Inner corners in all.
  /// Corner `id` in the board frame, mm.
  Eigen::Vector3d Corner(int id) const;
  /// All corners, by id.
  std::vector<Eigen::Vector3d> Corners() const;
  /// Width and height of the corner grid, mm.
  Eigen::Vector2d Extent() const;
  /// The spec string this board parses from (round trip of ParseBoardSpec).
  std::string ToString() const;
};

/// Parses `chessboard:9x6:25` or `charuco:5x7:40:30[:DICT_4X4_50]`; throws InputError naming the
/// text and the expected form.
BoardSpec ParseBoardSpec(const std::string& text);

}  // namespace lasercell::calib
