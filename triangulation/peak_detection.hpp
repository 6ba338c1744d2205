#pragma once
// Laser peak detection in raw sensor images: one peak per image column, as a laser-
// triangulation camera computes it on chip.
//
// Conventions: images are row-major gray (8 or 16 bit), width x height, pixel (u, v) at
// data[v * stride + u]; pixel centres at integer coordinates (mrcal/OpenCV), so a peak row of
// 12.0 is the centre of row 12. The laser line runs across the columns: each column holds (at
// most) one stripe crossing, whose subpixel row is estimated by one of three estimators
// (Fisher & Naidu, "A comparison of algorithms for subpixel peak detection", 1996; Blais &
// Rioux, "Real-time numerical peak detector", Signal Processing 11, 1986):
//   - centre of gravity of the samples above a threshold (threshold subtracted),
//   - Gaussian three-point fit (parabola through the logarithms of the top three samples),
//   - Blais-Rioux: zero crossing of the 4th-order FIR derivative g(i) = f(i+2) + f(i+1) -
//     f(i-1) - f(i-2), located by linear interpolation between the two samples around it.
// Output is a triangulation::Profile (row_px NaN = no peak; intensity = peak height above the
// background (Gaussian through the top three samples) / full scale, 0..1; width_px = FWHM by linear
// interpolation at half height) plus a per-column status: saturated (a sample at full scale inside
// the peak) and ambiguous (a second, separated peak at least `ambiguity_ratio` as high as the
// first: a reflection, an edge, a multi-path ghost) are reported, never silently mixed with clean
// peaks.

#include <cstdint>
#include <string>
#include <vector>

#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {

/// Sub-pixel estimator of the peak row.
enum class PeakEstimator {
  kCenterOfGravity,  ///< Threshold-subtracted centre of gravity of the peak's samples.
  kGaussian,         ///< Gaussian through the top sample and its two neighbours.
  kBlaisRioux,       ///< Zero crossing of the 4th-order FIR derivative (linear interpolation).
};

/// "cog", "gaussian", "blais-rioux".
std::string PeakEstimatorName(PeakEstimator estimator);
/// Parses a name of PeakEstimatorName (also "br", "center-of-gravity"); throws OptionError.
PeakEstimator ParsePeakEstimator(const std::string& name);

/// How a column's peak was classified.
enum class PeakStatus : std::uint8_t {
  kNoPeak = 0,     ///< Nothing above the thresholds (row NaN).
  kValid = 1,      ///< One clean peak.
  kSaturated = 2,  ///< The peak holds a sample at full scale (estimate biased; see options).
  kAmbiguous = 3,  ///< Two separated peaks of comparable height (reflection / ghost).
};

/// Thresholds and policies of the detector.
struct PeakDetectionOptions {
  PeakEstimator estimator = PeakEstimator::kGaussian;  ///< Sub-pixel estimator.
  /// Minimum peak height above the column background, in gray levels of the image's own scale
  /// (8-bit: 0..255, 16-bit: 0..65535). Default 20 (8-bit images with ~1.5 levels of noise).
  double min_height = 20.0;
  /// Centre-of-gravity threshold as a fraction of the peak height above background, [0, 1):
  /// samples above background + fraction * height contribute (minus the threshold).
  double cog_threshold_fraction = 0.5;
  /// A second peak separated from the first by a dip below half height, at least this fraction
  /// of the first's height, makes the column ambiguous. (0, 1]; 1 disables it in practice.
  double ambiguity_ratio = 0.5;
  /// Gray level counted as saturated; <= 0: full scale of the pixel type (255 or 65535).
  double saturation_level = 0.0;
  /// Drop (row NaN) ambiguous columns instead of reporting the stronger peak.
  bool reject_ambiguous = false;
  /// Drop saturated columns instead of reporting them (their row comes from the centre of
  /// gravity of the clipped plateau, whatever the estimator, since a clipped top has no shape).
  bool reject_saturated = false;
  int first_row = -1;  ///< First row searched (ROI; -1: from the top).
  int last_row = -1;   ///< Last row searched (ROI; -1: to the bottom).
  /// The stripe runs along the image columns (a vertical line, e.g. a camera turned by 90 deg):
  /// detect one peak per image ROW instead. The result's "columns" are then image rows and its
  /// row_px are image columns (sub-pixel); first_row/last_row bound the searched image columns.
  bool peaks_per_row = false;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "PeakDetectionOptions") const;
};

/// A read-only view of a gray image (row-major; stride in pixels, >= width).
template <typename Pixel>
struct ImageView {
  const Pixel* data = nullptr;
  int width = 0;
  int height = 0;
  int stride = 0;  ///< Pixels from one row to the next (0: width).
};
using ImageView8 = ImageView<std::uint8_t>;
using ImageView16 = ImageView<std::uint16_t>;

/// Peaks of one image.
struct PeakDetectionResult {
  Profile profile;                 ///< One entry per column (full image width).
  std::vector<PeakStatus> status;  ///< Per column.
  std::vector<float> background;   ///< Per column: background level, gray levels.
  std::size_t valid = 0;           ///< Columns with a clean peak.
  std::size_t saturated = 0;       ///< Columns whose peak is saturated.
  std::size_t ambiguous = 0;       ///< Columns with two separated peaks.
  std::size_t no_peak = 0;         ///< Columns without a peak.

  /// e.g. "1024 columns: 1000 valid, 3 saturated, 5 ambiguous, 16 without peak (gaussian)".
  std::string Summary() const;
  PeakEstimator estimator = PeakEstimator::kGaussian;
};

/// Detects one peak per column of an 8-bit image. Throws InputError for an empty/invalid view
/// and OptionError for bad options (or an ROI outside the image).
PeakDetectionResult DetectPeaks(const ImageView8& image, const PeakDetectionOptions& options);
/// The same for a 16-bit image (thresholds in 16-bit gray levels).
PeakDetectionResult DetectPeaks(const ImageView16& image, const PeakDetectionOptions& options);

/// The estimators on one column of background-subtracted samples (exposed for tests):
/// subpixel row of the peak whose top sample is `top`, or NaN when the estimator has no
/// answer there (e.g. the top at the column's end).
double EstimatePeakRow(const float* column, int size, int top, PeakEstimator estimator,
                       double cog_threshold);

}  // namespace lasercell::triangulation
