#pragma once
// Detection of calibration boards (calib/board.hpp) in 8-bit gray images (core/image8.hpp), with
// a diagnosis when a board is not found.
//
// Chessboards: OpenCV's findChessboardCornersSB (falling back to findChessboardCorners), then
// cornerSubPix refinement with a window derived from the board's square size in pixels (SB's own
// subpixel corners are biased by up to ~0.1 px on strongly tilted views; cornerSubPix with a
// window inside one square stays < 0.05 px). ChArUco: ArUco markers (OpenCV 4.6 aruco),
// interpolateCornersCharuco, then the same cornerSubPix refinement.
//
// Pixels: the centre of the top-left pixel is (0, 0) (OpenCV and mrcal convention).
// No OpenCV type appears in this header.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "core/image8.hpp"

namespace lasercell::calib {

/// Decodes PNG/JPEG/... bytes (any format OpenCV's imdecode reads) to gray (one channel); nullopt
/// when the bytes are not a readable image.
std::optional<Image8> DecodeGrayImage(const std::string& bytes);

enum class DetectionStatus {
  kFound,           ///< Corners detected.
  kUnreadable,      ///< The bytes are not an image.
  kNotFound,        ///< No board of the given geometry in the image.
  kWrongBoardSize,  ///< A chessboard of another size was found: the --board spec is suspect.
  kTooFewCorners,   ///< ChArUco: fewer corners than DetectionOptions::min_charuco_corners.
};

/// "found", "unreadable", "not_found", "wrong_board_size", "too_few_corners".
const char* DetectionStatusName(DetectionStatus status);

struct DetectionOptions {
  /// Refine the corners with cornerSubPix (half window from the square size in px).
  bool refine = true;
  /// Half window of the refinement as a fraction of the smallest square edge in px (the window
  /// must stay inside the squares around a corner: < 0.5).
  double refine_window_fraction = 0.4;
  /// Bounds of the refinement half window, px.
  int min_refine_half_window_px = 2;
  int max_refine_half_window_px = 15;
  /// When the first search fails, look for a chessboard of any size to diagnose a wrong --board
  /// spec (one more detection pass on failed images only). A visible grid too small to hold the
  /// board also skips the slower fallback searches, which could not find it.
  bool diagnose_board_size = true;
  /// ChArUco views with fewer interpolated corners are rejected.
  int min_charuco_corners = 6;
  /// Search for the board on the image shrunk by this integer factor (area average), then refine
  /// the corners at full resolution: about factor^2 less search time on large images whose
  /// squares stay >= ~10 px when shrunk. 1 (default): search at full resolution. > 1 needs
  /// `refine` (the search's corners are only good to ~factor/2 px).
  int search_downscale = 1;

  /// Throws OptionError naming the field.
  void Check() const;
};

/// The board in one image.
struct TargetDetection {
  DetectionStatus status = DetectionStatus::kNotFound;
  std::string message;  ///< Human-readable diagnosis ("found 54 corners", ...).
  int width = 0;        ///< Image size, px.
  int height = 0;
  std::vector<Eigen::Vector2d> corners_px;  ///< Detected corners.
  std::vector<int> corner_ids;              ///< BoardSpec corner id of each corner.
  double square_px = 0;                     ///< Smallest square edge seen in the image, px.
  int refine_half_window_px = 0;            ///< cornerSubPix half window used (0: no refinement).
  double max_refine_shift_px = 0;           ///< Largest move of a corner by the refinement.

  bool found() const { return status == DetectionStatus::kFound; }
};

/// Detects `board` in a gray (one-channel) `image`. Never throws for image content (the status
/// says what happened; kUnreadable for an empty or non-gray image); throws OptionError for bad
/// options or board.
TargetDetection DetectTarget(const Image8& image, const BoardSpec& board,
                             const DetectionOptions& options = {});

/// Decodes `bytes` and detects; an undecodable image gives status kUnreadable.
TargetDetection DetectTargetInEncodedImage(const std::string& bytes, const BoardSpec& board,
                                           const DetectionOptions& options = {});

}  // namespace lasercell::calib
