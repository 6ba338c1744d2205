#pragma once
// Detection of calibration boards (calib/board.hpp) in 8-bit gray images (core/image8.hpp), with
// a diagnosis when a board is not found.
//
// Chessboards: a fixed cascade of OpenCV detectors, tried in this order on the search image
// (DetectionOptions::search_downscale) until one returns the whole board:
//   1. "sb_normalize":                     findChessboardCornersSB, NORMALIZE_IMAGE
//   2. "sb_normalize_accuracy":            findChessboardCornersSB, NORMALIZE_IMAGE | ACCURACY
//   3. "sb_normalize_exhaustive_accuracy": findChessboardCornersSB, NORMALIZE_IMAGE | EXHAUSTIVE
//                                          | ACCURACY
//   4. "classic_adaptive_normalize":       findChessboardCorners, ADAPTIVE_THRESH |
//                                          NORMALIZE_IMAGE
// (CALIB_CB_ flags; TargetDetection::detector names the one that succeeded; SB without NORMALIZE
// is left out: it takes a board's outer edge for one more row of corners, i.e. finds boards of
// the wrong size), then cornerSubPix refinement at full resolution with a window derived from the
// board's square size in pixels (SB's own subpixel corners are biased by up to ~0.1 px on strongly
// tilted views; cornerSubPix with a window inside one square stays < 0.05 px). ChArUco: ArUco
// markers (OpenCV 4.6 aruco), interpolateCornersCharuco, then the same cornerSubPix refinement. A
// board any of those detectors finds is found: the board-size diagnosis (a probe for a chessboard
// of any size) runs only after all of them failed, and only words the failure. Corner order of a
// chessboard: row-major, `cols` corners per row, the grid right-handed in the image (corner 1 -
// corner 0 crossed with corner cols - corner 0 is > 0 with y down), i.e. the board's z points away
// from the camera; which of the two such orders (a half turn apart) is returned is the detector's
// choice.
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
  /// A corner the refinement moves farther than this from the detector's estimate (px, times
  /// search_downscale) is suspect: it may have run onto another edge -- near a board's outer
  /// corners a window of 0.4 squares can reach the board's rim or the background, and real
  /// views showed 3-9 px jumps there -- or the detector's estimate may have been off (SB's
  /// corners on strongly foreshortened squares, seen 3 px off). It is refined again with
  /// halved windows down to min_refine_half_window_px, and of those results and the detector's
  /// estimate the one nearest the homography of its trusted grid neighbours is kept; without 6
  /// such neighbours, the first halved window within the limit, else the estimate (> 0).
  double refine_shift_limit_px = 1.5;
  /// When every detector of the cascade failed, look for a chessboard of any size to diagnose a
  /// wrong --board spec (one more detection pass on failed images only). Only words the failure
  /// (kWrongBoardSize): it never skips a detector.
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
  /// Corners refined again with a smaller window / left unrefined (refine_shift_limit_px).
  int rerefined_corners = 0, unrefined_corners = 0;
  /// Positions (into corners_px) of the corners refined again.
  std::vector<int> rerefined;
  /// The detector that found the board: a chessboard cascade name ("sb_normalize", ...,
  /// "classic_adaptive_normalize"; see the preamble), "charuco", or "" when not found.
  std::string detector;

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
