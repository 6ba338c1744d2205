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

/// Cross-section of the laser stripe along an image column, for RenderLaserLine: what a real
/// sensor sees instead of the point-sampled Gaussian (on which the Gaussian three-point estimator
/// is exact by construction). The defaults reproduce that point-sampled Gaussian bit for bit.
///
/// Per column, with r = ExposureTruth::row_px (the ground truth), s = width_px / 2.3548 (FWHM ->
/// sigma) and A = 255 * intensity * peak_gain gray levels:
///   profile  f(t) = A exp(-t^2 / (2 s_t^2)), t = row - r, s_t = (1 - asymmetry) s for t < 0 and
///            (1 + asymmetry) s for t >= 0 (two half-Gaussians of the same peak; the FWHM stays
///            1.1774 ((1 - a) + (1 + a)) s = width_px);
///   pixel    f at the pixel centre (integrate_pixel_area false), or the mean of f over the pixel's
///            extent [row - 1/2, row + 1/2] (true: a pixel integrates light over its area, fill
///            factor 1; closed form with erf);
///   speckle  times a multiplicative field of mean 1 and contrast speckle_contrast (std / mean),
///            one value per pixel, correlated along the column, fresh per column;
///   then     + ambient, read noise, rounding and clipping to 0..255 (ImageRenderOptions).
/// Ground truth in every case is r, the beam centre = the profile's mode. An asymmetric profile
/// stands for the skewed image of the spot on a tilted surface: an estimator's shift towards the
/// wider side (the centroid moves by sqrt(2 / pi) * 2 a s) is real error a sensor would make
/// there (peak detectors on such non-ideal stripes: Forest, Salvi, Cabruja & Pous, "Laser stripe
/// peak detector for 3D scanners. A FIR filter approach", ICPR 2004).
struct StripeShape {
  /// a in [-0.9, 0.9]: half-Gaussian widths (1 - a) s above (smaller rows) and (1 + a) s below
  /// the mode; a > 0 puts the wider side towards larger rows. 0: symmetric.
  double asymmetry = 0.0;
  /// Average the profile over each pixel's extent (box filter of 1 px) instead of sampling it at
  /// the pixel centre.
  bool integrate_pixel_area = false;
  /// Speckle contrast C = std / mean of the multiplicative field, [0, 1]; 0: no speckle. The
  /// field is log-normal, exp(sigma_l g - sigma_l^2 / 2) with sigma_l^2 = ln(1 + C^2), g a
  /// unit-variance Gaussian process: mean 1, contrast exactly C, always positive (partially
  /// developed speckle averaged by the pixel; Goodman, "Speckle Phenomena in Optics", 2007;
  /// its effect on triangulation: Dorsch, Haeusler & Herrmann, Appl. Opt. 33(7), 1994).
  double speckle_contrast = 0.0;
  /// Speckle grain along the column, px, [0.5, 50]: g has the Gaussian autocorrelation
  /// exp(-d^2 / (2 grain^2)) at a lag of d rows (white noise filtered by a Gaussian of
  /// sigma grain / sqrt(2), sampled at whole rows: exact to < 1e-4 for grains >= 1 px).
  double speckle_grain_px = 1.5;
  /// Factor on the exposure's intensity, (0, 100]: > 1 models an over-long exposure whose top
  /// clips at 255 in the 8-bit quantization.
  double peak_gain = 1.0;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "stripe") const;
};

/// Named stripe shapes (StripeShapePresetNames() order):
///  - "sampled-gaussian": the defaults, a Gaussian sampled at the pixel centres;
///  - "pixel-area": the Gaussian integrated over each pixel;
///  - "asymmetric": half-Gaussians of 0.7 s and 1.3 s (asymmetry 0.3), pixel-integrated;
///  - "speckle": pixel-integrated Gaussian times speckle of contrast 0.25, grain 1.5 px;
///  - "saturated": pixel-integrated Gaussian at peak_gain 4, its top clipped at 255.
/// Throws OptionError for another name (listing the known ones).
StripeShape StripeShapePreset(const std::string& name);
/// The preset names, in the order above.
std::vector<std::string> StripeShapePresetNames();

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
  /// The same with the stripe's cross-section given by `shape` (ghost peaks get the same shape);
  /// deterministic for a seed (read noise from `seed`, speckle from streams of it, one per
  /// column). StripeShape{} gives exactly the image of the overload above.
  Image8 RenderLaserLine(const ExposureTruth& exposure, const ImageRenderOptions& options,
                         const StripeShape& shape, std::uint64_t seed) const;

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
