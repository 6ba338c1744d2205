#include "triangulation/peak_detection.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.hpp"

namespace lasercell::triangulation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Rows [lo, hi] of a column after background subtraction around its top sample.
struct PeakExtent {
  int left = 0;   // first sample above half height
  int right = 0;  // last sample above half height
  double fwhm_px = 0;
};

PeakExtent HalfHeightExtent(const float* f, int r0, int r1, int top) {
  const float half = 0.5f * f[top];
  PeakExtent e;
  e.left = top;
  while (e.left > r0 && f[e.left - 1] > half) --e.left;
  e.right = top;
  while (e.right < r1 && f[e.right + 1] > half) ++e.right;
  // Linear interpolation of the half-height crossings (the extent's ends when clipped by the ROI).
  double xl = e.left, xr = e.right;
  if (e.left > r0) {
    const double a = f[e.left - 1], b = f[e.left];
    xl = e.left - 1 + (half - a) / (b - a);
  }
  if (e.right < r1) {
    const double a = f[e.right], b = f[e.right + 1];
    xr = e.right + (a - half) / (a - b);
  }
  e.fwhm_px = xr - xl;
  return e;
}

// Highest sample beyond the main peak's monotone descent on one side (step -1 or +1), if it is
// a separate peak: at least `min_value` and separated from the main peak by a dip below half its
// own height. Returns its value or 0.
float SecondaryPeak(const float* f, int r0, int r1, int start, int step, float min_value) {
  int i = start;
  // Follow the descent of the main peak's tail.
  while (i + step >= r0 && i + step <= r1 && f[i + step] <= f[i]) i += step;
  float best = 0;
  int best_index = -1;
  for (int j = i + step; j >= r0 && j <= r1; j += step) {
    if (f[j] > best) {
      best = f[j];
      best_index = j;
    }
  }
  if (best_index < 0 || best < min_value) return 0;
  float dip = best;
  for (int j = best_index; j != start; j -= step) dip = std::min(dip, f[j]);
  dip = std::min(dip, f[start]);
  return dip <= 0.5f * best ? best : 0.0f;
}

template <typename Pixel>
PeakDetectionResult Detect(const ImageView<Pixel>& image, const PeakDetectionOptions& options,
                           double full_scale) {
  options.Check();
  if (image.data == nullptr || image.width <= 0 || image.height <= 0) {
    throw InputError("peak detection: empty image (width " + std::to_string(image.width) +
                     ", height " + std::to_string(image.height) + ")");
  }
  const int stride = image.stride == 0 ? image.width : image.stride;
  if (stride < image.width) {
    throw InputError("peak detection: image stride " + std::to_string(stride) +
                     " is smaller than its width " + std::to_string(image.width));
  }
  if (options.peaks_per_row) {
    // Transpose once and detect per column of the transpose.
    std::vector<Pixel> transposed(static_cast<std::size_t>(image.width) * image.height);
    for (int v = 0; v < image.height; ++v) {
      for (int u = 0; u < image.width; ++u) {
        transposed[static_cast<std::size_t>(u) * image.height + v] =
            image.data[static_cast<std::size_t>(v) * stride + u];
      }
    }
    PeakDetectionOptions columns = options;
    columns.peaks_per_row = false;
    return Detect(ImageView<Pixel>{transposed.data(), image.height, image.width, 0}, columns,
                  full_scale);
  }
  const int r0 = options.first_row < 0 ? 0 : options.first_row;
  const int r1 = options.last_row < 0 ? image.height - 1 : options.last_row;
  if (r0 > r1 || r1 >= image.height) {
    throw OptionError("PeakDetectionOptions.first_row/last_row: rows [" + std::to_string(r0) +
                      ", " + std::to_string(r1) + "] are not inside the image's " +
                      std::to_string(image.height) + " rows");
  }
  const double saturation = options.saturation_level > 0 ? options.saturation_level : full_scale;

  const auto width = static_cast<std::uint32_t>(image.width);
  PeakDetectionResult result;
  result.estimator = options.estimator;
  result.profile = Profile::Empty(width);
  result.status.assign(width, PeakStatus::kNoPeak);
  result.background.assign(width, 0.0f);
  std::vector<float> raw(static_cast<std::size_t>(image.height));
  std::vector<float> f(static_cast<std::size_t>(image.height));
  std::vector<float> scratch;
  for (int u = 0; u < image.width; ++u) {
    for (int v = r0; v <= r1; ++v) {
      raw[v] = static_cast<float>(image.data[static_cast<std::size_t>(v) * stride + u]);
    }
    // Background: the column median (the stripe covers a few rows of hundreds); 8-bit columns
    // by a 256-bin histogram (5x faster than nth_element), others by nth_element.
    float background = 0;
    if constexpr (sizeof(Pixel) == 1) {
      std::array<int, 256> hist{};
      for (int v = r0; v <= r1; ++v) ++hist[static_cast<std::size_t>(raw[v])];
      const int half = (r1 - r0 + 1) / 2;  // the element nth_element would pick
      int seen = 0, level = 0;
      while (seen + hist[level] <= half) seen += hist[level++];
      background = static_cast<float>(level);
    } else {
      scratch.assign(raw.begin() + r0, raw.begin() + r1 + 1);
      const auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
      std::nth_element(scratch.begin(), mid, scratch.end());
      background = *mid;
    }
    result.background[u] = background;
    int top = r0;
    for (int v = r0; v <= r1; ++v) {
      f[v] = raw[v] - background;
      if (f[v] > f[top]) top = v;
    }
    const float height = f[top];
    if (height < options.min_height) {
      ++result.no_peak;
      continue;
    }
    const PeakExtent extent = HalfHeightExtent(f.data(), r0, r1, top);
    bool saturated = false;
    for (int v = extent.left; v <= extent.right; ++v) saturated |= raw[v] >= saturation;
    const float min_second = std::max(static_cast<float>(options.ambiguity_ratio) * height,
                                      static_cast<float>(options.min_height));
    const bool ambiguous = SecondaryPeak(f.data(), r0, r1, extent.left, -1, min_second) > 0 ||
                           SecondaryPeak(f.data(), r0, r1, extent.right, +1, min_second) > 0;
    PeakStatus status = saturated ? PeakStatus::kSaturated
                                  : (ambiguous ? PeakStatus::kAmbiguous : PeakStatus::kValid);
    if (saturated && ambiguous) status = PeakStatus::kAmbiguous;
    result.status[u] = status;
    const bool drop = (status == PeakStatus::kAmbiguous && options.reject_ambiguous) ||
                      (status == PeakStatus::kSaturated && options.reject_saturated);
    if (status == PeakStatus::kValid) ++result.valid;
    if (status == PeakStatus::kSaturated) ++result.saturated;
    if (status == PeakStatus::kAmbiguous) ++result.ambiguous;
    if (drop) continue;
    // A clipped top has no shape: the plateau's centre of gravity is the only fair estimate.
    const PeakEstimator estimator = saturated ? PeakEstimator::kCenterOfGravity : options.estimator;
    const double row = EstimatePeakRow(f.data() + r0, r1 - r0 + 1, top - r0, estimator,
                                       options.cog_threshold_fraction * height);
    if (std::isnan(row)) continue;
    result.profile.row_px[u] = static_cast<float>(row + r0);
    // Height at the peak, not at its nearest sample (up to 7 % lower for a 3 px stripe): the
    // Gaussian through the top three samples, when they allow it.
    double peak = height;
    if (!saturated && top > r0 && top < r1 && f[top - 1] > 0 && f[top + 1] > 0) {
      const double a = std::log(f[top - 1]), b = std::log(f[top]), c = std::log(f[top + 1]);
      const double den = a - 2 * b + c;
      if (den < 0)
        peak = std::clamp(std::exp(b - (a - c) * (a - c) / (8 * den)), 1.0 * height, 1.5 * height);
    }
    result.profile.intensity[u] = static_cast<float>(std::min(1.0, peak / full_scale));
    result.profile.width_px[u] = static_cast<float>(extent.fwhm_px);
  }
  return result;
}

}  // namespace

std::string PeakEstimatorName(PeakEstimator estimator) {
  switch (estimator) {
    case PeakEstimator::kCenterOfGravity:
      return "cog";
    case PeakEstimator::kGaussian:
      return "gaussian";
    case PeakEstimator::kBlaisRioux:
      return "blais-rioux";
  }
  return "?";
}

PeakEstimator ParsePeakEstimator(const std::string& name) {
  if (name == "cog" || name == "center-of-gravity") return PeakEstimator::kCenterOfGravity;
  if (name == "gaussian") return PeakEstimator::kGaussian;
  if (name == "blais-rioux" || name == "br") return PeakEstimator::kBlaisRioux;
  throw OptionError("peak estimator '" + name + "' is unknown; use cog, gaussian or blais-rioux");
}

void PeakDetectionOptions::Check(const std::string& what) const {
  if (!(min_height > 0) || !std::isfinite(min_height)) {
    throw OptionError(what + ".min_height must be a positive gray level, got " +
                      std::to_string(min_height));
  }
  if (!(cog_threshold_fraction >= 0 && cog_threshold_fraction < 1)) {
    throw OptionError(what + ".cog_threshold_fraction must be in [0, 1), got " +
                      std::to_string(cog_threshold_fraction));
  }
  if (!(ambiguity_ratio > 0 && ambiguity_ratio <= 1)) {
    throw OptionError(what + ".ambiguity_ratio must be in (0, 1], got " +
                      std::to_string(ambiguity_ratio));
  }
  if (!std::isfinite(saturation_level)) {
    throw OptionError(what + ".saturation_level must be finite (<= 0: full scale)");
  }
  if (first_row < -1 || last_row < -1) {
    throw OptionError(what + ".first_row/last_row must be >= 0 (or -1 for the whole column)");
  }
}

std::string PeakDetectionResult::Summary() const {
  char b[200];
  std::snprintf(
      b, sizeof b, "%zu columns: %zu valid, %zu saturated, %zu ambiguous, %zu without peak (%s)",
      status.size(), valid, saturated, ambiguous, no_peak, PeakEstimatorName(estimator).c_str());
  return b;
}

double EstimatePeakRow(const float* f, int size, int top, PeakEstimator estimator,
                       double cog_threshold) {
  switch (estimator) {
    case PeakEstimator::kCenterOfGravity: {
      // Contiguous samples above the threshold around the top, weights f - threshold (Fisher &
      // Naidu 1996: subtracting the threshold removes most of the truncation bias).
      const double t = cog_threshold;
      double sw = 0, swy = 0;
      for (int i = top; i >= 0 && f[i] > t; --i) {
        sw += f[i] - t;
        swy += (f[i] - t) * i;
      }
      for (int i = top + 1; i < size && f[i] > t; ++i) {
        sw += f[i] - t;
        swy += (f[i] - t) * i;
      }
      return sw > 0 ? swy / sw : static_cast<double>(top);
    }
    case PeakEstimator::kGaussian: {
      if (top < 1 || top + 1 >= size) return kNaN;
      // Logarithms of the top three samples; neighbours at or below the background are clamped to
      // 1 % of the top (a very narrow peak), which bounds the step to half a pixel.
      const double floor = 0.01 * f[top];
      const double a = std::log(std::max<double>(f[top - 1], floor));
      const double b = std::log(std::max<double>(f[top], floor));
      const double c = std::log(std::max<double>(f[top + 1], floor));
      const double den = a - 2 * b + c;
      if (!(den < 0)) return top;  // flat top (e.g. equal samples): the top itself
      return top + std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
    }
    case PeakEstimator::kBlaisRioux: {
      if (top < 3 || top + 3 >= size) return kNaN;
      // 4th-order FIR derivative (Blais & Rioux 1986): positive left of the peak, negative right.
      const auto g = [f](int i) { return double(f[i + 2]) + f[i + 1] - f[i - 1] - f[i - 2]; };
      const double g0 = g(top);
      int i = top;
      double gi = g0, gj = g(top + 1);
      if (g0 < 0) {
        i = top - 1;
        gi = g(top - 1);
        gj = g0;
      }
      if (gi == gj) return i + 0.5;
      return i + std::clamp(gi / (gi - gj), 0.0, 1.0);
    }
  }
  return kNaN;
}

PeakDetectionResult DetectPeaks(const ImageView8& image, const PeakDetectionOptions& options) {
  return Detect(image, options, 255.0);
}

PeakDetectionResult DetectPeaks(const ImageView16& image, const PeakDetectionOptions& options) {
  return Detect(image, options, 65535.0);
}

}  // namespace lasercell::triangulation
