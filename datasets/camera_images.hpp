#pragma once
// Camera images of the simulated sensor: chessboard views for intrinsics calibration and raw
// laser-line images for peak-detector tests, rendered through the true lens model.
//
// Chessboard rendering is exact up to the anti-aliasing: the board is planar, so every camera
// ray (mrcal unprojection of the pixel corners, cached once per camera and interpolated
// bilinearly inside a pixel) meets it through a homography. A pixel wholly inside one square
// takes that square's albedo; a pixel an edge crosses is averaged over edge_samples^2
// sub-samples (box filter = the pixel's area) on an n-rooks pattern (edge_samples^2 distinct x
// and y offsets: an axis-aligned edge is resolved to 1 / edge_samples^2 px). Then: cos^4
// vignetting, Gaussian optical blur, Gaussian read noise, 8-bit quantization. Gray = ambient +
// exposure * albedo * vignetting.
//
// Frames: camera as in sensor.hpp; target frame (the rendered board's, of every camera_from_board
// here and in the truth files): pattern in its xy plane (z = 0, +z out of the printed face),
// origin at the pattern's outer corner, square (i, j) at [i s, (i+1) s] x [j s, (j+1) s], dark
// when i + j is even (as Material in scene.hpp), inner corner (i, j) at ((i+1) s, (j+1) s, 0).
// calib::BoardSpec's chessboard frame (calib/board.hpp) has the same axes and its origin at the
// first inner corner: ChessboardTarget::TargetFromBoard() is the one relation between the two.
// Images are 8-bit gray (Image8, core/image8.hpp), width x height of the camera.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "core/image8.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/sensor.hpp"

namespace lasercell::datasets {

/// A printed chessboard on a plate: the board a calibration sees (calib::BoardSpec, inner
/// corners) and what only the renderer needs (margin, albedos).
struct ChessboardTarget {
  /// The chessboard: cols x rows inner corners (SquaresX() x SquaresY() squares) of square_mm.
  calib::BoardSpec board = calib::BoardSpec::Chessboard(9, 6, 40.0);
  double border_mm = 20.0;     ///< Light margin around the pattern.
  double dark_albedo = 0.04;   ///< Dark squares.
  double light_albedo = 0.85;  ///< Light squares and border.

  /// Squares along the target's x (inner corners + 1) and y.
  int SquaresX() const { return board.cols + 1; }
  int SquaresY() const { return board.rows + 1; }
  /// target_from_board: BoardSpec's chessboard frame (origin at the first inner corner) in the
  /// target frame (origin at the pattern's outer corner): same axes, translated by one square
  /// along x and y, (square_mm, square_mm, 0).
  Eigen::Isometry3d TargetFromBoard() const;
  /// board.Corners() (OpenCV order, BoardSpec ids) in the target frame, mm:
  /// TargetFromBoard() * board.Corner(id), corner (c, r) exactly at ((c+1) s, (r+1) s, 0).
  std::vector<Eigen::Vector3d> CornersInTarget() const;
  /// Throws OptionError naming `what` and the field (`what`.squares for the corner counts).
  void Check(const std::string& what = "chessboard") const;
};

/// Photometry and image noise.
struct ImageRenderOptions {
  double exposure = 250.0;          ///< Gray level of albedo 1 on the optical axis.
  double ambient = 6.0;             ///< Gray level offset (dark current, stray light).
  double background_albedo = 0.25;  ///< Albedo seen where the ray misses the plate.
  double blur_sigma_px = 0.6;       ///< Gaussian optical blur (0: none).
  double noise_sigma = 1.5;         ///< Gaussian read noise, gray levels (0: none).
  bool vignetting = true;           ///< cos^4 falloff.
  int edge_samples = 16;            ///< Sub-samples per axis in pixels an edge crosses.

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "images") const;
};

/// Renders images through one camera. Construction unprojects every pixel corner once.
class ImageRenderer {
 public:
  explicit ImageRenderer(const calib::CameraModel& camera);

  /// The chessboard at camera_from_board (target frame); noise from `seed`.
  Image8 RenderChessboard(const ChessboardTarget& target,
                          const Eigen::Isometry3d& camera_from_board,
                          const ImageRenderOptions& options, std::uint64_t seed) const;

  /// A raw sensor image of one exposure's laser line: per column a Gaussian stripe of the
  /// exposure's exact row, FWHM width and intensity (saturating at 255) over a dark ambient, with
  /// read noise; for peak-detector tests.
  Image8 RenderLaserLine(const ExposureTruth& exposure, const ImageRenderOptions& options,
                         std::uint64_t seed) const;

  const calib::CameraModel& camera() const { return camera_; }

 private:
  calib::CameraModel camera_;
  std::vector<Eigen::Vector2d> corner_rays_;  // normalized (x/z, y/z) at pixel corners
};

/// `count` varied camera_from_board poses (target frame; distance 550..850 mm, tilt 5..40 deg,
/// any yaw, spread over the image) with the whole plate in view and every inner corner >= 25 px
/// inside the image.
std::vector<Eigen::Isometry3d> DrawChessboardPoses(const ChessboardTarget& target,
                                                   const calib::CameraModel& camera, int count,
                                                   std::uint64_t seed);

/// PNG bytes of an image, gray or BGR (OpenCV imgcodecs; deterministic).
std::string EncodePng(const Image8& image);

}  // namespace lasercell::datasets
