#include "triangulation/peak_detection.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "datasets/camera_images.hpp"
#include "datasets/rng.hpp"

namespace lasercell::triangulation {
namespace {

constexpr double kFwhmToSigma = 1.0 / 2.3548200450309493;

// A raw image of a Gaussian stripe (point-sampled, as datasets::RenderLaserLine) at `rows[u]`
// in column u, amplitude `amplitude` over `ambient`, white noise `noise`, rounded and clipped
// to the pixel type's full scale.
template <typename Pixel>
std::vector<Pixel> StripeImage(int w, int h, const std::vector<double>& rows, double fwhm,
                               double amplitude, double ambient, double noise, std::uint64_t seed,
                               double full_scale) {
  datasets::Rng rng(seed);
  std::vector<Pixel> img(static_cast<std::size_t>(w) * h);
  const double s = fwhm * kFwhmToSigma;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double d = (v - rows[u]) / s;
      double g = ambient + amplitude * std::exp(-0.5 * d * d) + noise * rng.Normal();
      g = std::clamp(std::round(g), 0.0, full_scale);
      img[static_cast<std::size_t>(v) * w + u] = static_cast<Pixel>(g);
    }
  }
  return img;
}

std::vector<double> PhaseRows(int w, double base) {
  std::vector<double> rows(w);
  for (int u = 0; u < w; ++u) rows[u] = base + 0.37 * u + std::fmod(0.6180339887 * u, 1.0);
  return rows;
}

const PeakEstimator kAll[] = {PeakEstimator::kCenterOfGravity, PeakEstimator::kGaussian,
                              PeakEstimator::kBlaisRioux};

// Noise-free 16-bit stripes (quantization 1/65535 of the height): the Gaussian three-point
// estimator is exact for a sampled Gaussian; the others have a known systematic subpixel error
// (S-curve) that stays well below a tenth of a pixel at FWHM 3 px.
TEST(PeakDetection, EstimatorsOnNoiseFreeStripes) {
  const int w = 400, h = 64;
  std::vector<double> truth(w);  // 20..40 with every subpixel phase
  for (int u = 0; u < w; ++u) truth[u] = 20.0 + std::fmod(0.6180339887 * u, 1.0) + (u % 20);
  const auto img = StripeImage<std::uint16_t>(w, h, truth, 3.0, 40000, 1000, 0, 1, 65535);
  for (const PeakEstimator e : kAll) {
    PeakDetectionOptions o;
    o.estimator = e;
    o.min_height = 1000;
    const PeakDetectionResult r = DetectPeaks(ImageView16{img.data(), w, h, 0}, o);
    EXPECT_EQ(r.valid, static_cast<std::size_t>(w)) << r.Summary();
    double worst = 0;
    for (int u = 0; u < w; ++u) {
      ASSERT_FALSE(std::isnan(r.profile.row_px[u]));
      worst = std::max(worst, std::abs(r.profile.row_px[u] - truth[u]));
      EXPECT_NEAR(r.profile.width_px[u], 3.0, 0.25);  // linear interpolation of the FWHM
      EXPECT_NEAR(r.profile.intensity[u], 40000.0 / 65535.0, 0.02);
    }
    std::printf("%s: worst noise-free error %.5f px\n", PeakEstimatorName(e).c_str(), worst);
    EXPECT_LT(worst, e == PeakEstimator::kGaussian ? 1e-3 : 0.1) << PeakEstimatorName(e);
  }
}

// Noisy 8-bit stripes from the simulator's laser-line renderer: every estimator's scatter is
// at least the Cramer-Rao bound of a Gaussian peak in white noise, sigma_mu = (sigma_n / A) *
// sqrt(2 s / sqrt(pi)) (s the Gaussian sigma; noise incl. quantization 1/12), and within a
// small factor of it; the error averages to zero over the subpixel phases.
// Simulation profile: ideal image noise (1.5 gray levels); the stripe rows are synthetic.
TEST(PeakDetection, SimulatedStripeImagesScatterNearTheCramerRaoBound) {
  const datasets::ImageRenderer renderer{datasets::MakeCameraModel()};
  datasets::ExposureTruth ex;
  const int w = 1024;
  ex.row_px.resize(w);
  ex.intensity.assign(w, 100.0 / 255.0);
  ex.width_px.assign(w, 3.0);
  for (int u = 0; u < w; ++u) ex.row_px[u] = 300.0 + 0.31 * u + std::fmod(0.6180339887 * u, 1.0);
  datasets::ImageRenderOptions io;
  io.noise_sigma = 1.5;
  const double s = 3.0 * kFwhmToSigma;
  const double sigma_n = std::sqrt(io.noise_sigma * io.noise_sigma + 1.0 / 12);
  const double crb = sigma_n / 100.0 * std::sqrt(2 * s / std::sqrt(std::numbers::pi));
  std::vector<Image8> images;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    images.push_back(renderer.RenderLaserLine(ex, io, seed));
  }
  for (const PeakEstimator e : kAll) {
    double sum = 0, sum2 = 0;
    int n = 0;
    for (const Image8& img : images) {
      PeakDetectionOptions o;
      o.estimator = e;
      const PeakDetectionResult r = DetectPeaks(ImageView8{img.pixels.data(), w, img.height, 0}, o);
      EXPECT_EQ(r.valid, static_cast<std::size_t>(w)) << r.Summary();
      for (int u = 0; u < w; ++u) {
        const double err = r.profile.row_px[u] - ex.row_px[u];
        sum += err;
        sum2 += err * err;
        ++n;
      }
    }
    const double mean = sum / n, rms = std::sqrt(sum2 / n);
    std::printf("%s: mean %.4f px, rms %.4f px, CRB %.4f px\n", PeakEstimatorName(e).c_str(), mean,
                rms, crb);
    EXPECT_GT(rms, 0.9 * crb) << PeakEstimatorName(e);
    EXPECT_LT(rms, 3.0 * crb) << PeakEstimatorName(e);
    // Averaged over all subpixel phases the S-curves cancel: only noise remains (5 sigma).
    EXPECT_LT(std::abs(mean), 5 * 3 * crb / std::sqrt(n)) << PeakEstimatorName(e);
  }
}

TEST(PeakDetection, SaturatedColumnsAreFlaggedAndCentredOnThePlateau) {
  const int w = 64, h = 64;
  std::vector<double> rows(w);
  for (int u = 0; u < w; ++u) rows[u] = 30.0 + 0.05 * u;
  // Columns >= 32 are twice over full scale: a clipped plateau.
  auto img = StripeImage<std::uint8_t>(w, h, rows, 4.0, 150, 5, 0.8, 3, 255);
  const auto hot = StripeImage<std::uint8_t>(w, h, rows, 4.0, 500, 5, 0.8, 3, 255);
  for (int v = 0; v < h; ++v) {
    for (int u = 32; u < w; ++u) img[v * w + u] = hot[v * w + u];
  }
  for (const PeakEstimator e : kAll) {
    PeakDetectionOptions o;
    o.estimator = e;
    const PeakDetectionResult r = DetectPeaks(ImageView8{img.data(), w, h, 0}, o);
    EXPECT_EQ(r.saturated, 32u);
    EXPECT_EQ(r.valid, 32u);
    for (int u = 0; u < w; ++u) {
      EXPECT_EQ(r.status[u], u >= 32 ? PeakStatus::kSaturated : PeakStatus::kValid);
      // The plateau spans ~2.5 px; its centre is the true row within the rounding of its ends.
      EXPECT_NEAR(r.profile.row_px[u], rows[u], u >= 32 ? 0.5 : 0.1) << "column " << u;
    }
    o.reject_saturated = true;
    const PeakDetectionResult dropped = DetectPeaks(ImageView8{img.data(), w, h, 0}, o);
    EXPECT_EQ(dropped.profile.ValidCount(), 32u);
  }
}

TEST(PeakDetection, SecondSeparatedPeaksMakeColumnsAmbiguous) {
  const int w = 60, h = 200;
  const std::vector<double> rows(w, 50.3);
  auto img = StripeImage<std::uint8_t>(w, h, rows, 3.0, 120, 6, 1.0, 5, 255);
  // Columns 20..39 get a ghost 40 rows lower at 60 % height; 40..59 a weak one at 20 %.
  for (int u = 20; u < w; ++u) {
    const double amp = u < 40 ? 72 : 24;
    for (int v = 80; v < 100; ++v) {
      const double d = (v - 90.0) / (3.0 * kFwhmToSigma);
      img[v * w + u] =
          static_cast<std::uint8_t>(std::min(255.0, img[v * w + u] + amp * std::exp(-0.5 * d * d)));
    }
  }
  PeakDetectionOptions o;
  const PeakDetectionResult r = DetectPeaks(ImageView8{img.data(), w, h, 0}, o);
  EXPECT_EQ(r.ambiguous, 20u) << r.Summary();
  EXPECT_EQ(r.valid, 40u) << r.Summary();
  for (int u = 0; u < w; ++u) {
    EXPECT_EQ(r.status[u], (u >= 20 && u < 40) ? PeakStatus::kAmbiguous : PeakStatus::kValid);
    EXPECT_NEAR(r.profile.row_px[u], 50.3, 0.1);  // the stronger peak is reported
  }
  o.reject_ambiguous = true;
  EXPECT_EQ(DetectPeaks(ImageView8{img.data(), w, h, 0}, o).profile.ValidCount(), 40u);
}

TEST(PeakDetection, DarkColumnsHaveNoPeakAndBadInputIsAnError) {
  const int w = 16, h = 32;
  std::vector<double> rows(w, 10.0);
  const auto img = StripeImage<std::uint8_t>(w, h, rows, 3.0, 10, 6, 1.0, 5, 255);
  const PeakDetectionResult r = DetectPeaks(ImageView8{img.data(), w, h, 0}, {});
  EXPECT_EQ(r.no_peak, static_cast<std::size_t>(w));  // 10 levels < min_height 20
  EXPECT_EQ(r.profile.ValidCount(), 0u);
  PeakDetectionOptions bad;
  bad.cog_threshold_fraction = 1.5;
  try {
    DetectPeaks(ImageView8{img.data(), w, h, 0}, bad);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("cog_threshold_fraction"), std::string::npos);
  }
  EXPECT_THROW(DetectPeaks(ImageView8{nullptr, w, h, 0}, {}), InputError);
  PeakDetectionOptions roi;
  roi.last_row = h;  // one past the end
  EXPECT_THROW(DetectPeaks(ImageView8{img.data(), w, h, 0}, roi), OptionError);
  EXPECT_THROW(ParsePeakEstimator("parabola"), OptionError);
}

TEST(PeakDetection, SixteenBitImagesGiveTheSameRowsAsScaledEightBitOnes) {
  const int w = 50, h = 40;
  const std::vector<double> rows = PhaseRows(w, 10.0);
  const auto img8 = StripeImage<std::uint8_t>(w, h, rows, 3.0, 150, 6, 0, 1, 255);
  std::vector<std::uint16_t> img16(img8.size());
  for (std::size_t i = 0; i < img8.size(); ++i)
    img16[i] = static_cast<std::uint16_t>(img8[i] * 257);
  PeakDetectionOptions o8, o16;
  o16.min_height = o8.min_height * 257;
  const auto r8 = DetectPeaks(ImageView8{img8.data(), w, h, 0}, o8);
  const auto r16 = DetectPeaks(ImageView16{img16.data(), w, h, 0}, o16);
  for (int u = 0; u < w; ++u) {
    EXPECT_NEAR(r8.profile.row_px[u], r16.profile.row_px[u], 1e-5);
    EXPECT_NEAR(r8.profile.intensity[u], r16.profile.intensity[u], 1e-6);
  }
}

TEST(PeakDetection, PeaksPerRowEqualPeaksPerColumnOfTheTransposedImage) {
  const int w = 50, h = 40;
  const std::vector<double> rows = PhaseRows(w, 10.0);
  const auto img = StripeImage<std::uint8_t>(w, h, rows, 3.0, 150, 6, 1.0, 7, 255);
  std::vector<std::uint8_t> transposed(img.size());
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) transposed[u * h + v] = img[v * w + u];
  }
  PeakDetectionOptions per_row;
  per_row.peaks_per_row = true;
  const auto by_row = DetectPeaks(ImageView8{transposed.data(), h, w, 0}, per_row);
  const auto by_column = DetectPeaks(ImageView8{img.data(), w, h, 0}, {});
  ASSERT_EQ(by_row.profile.row_px.size(), static_cast<std::size_t>(w));
  EXPECT_EQ(by_row.profile.row_px, by_column.profile.row_px);
  EXPECT_EQ(by_row.valid, static_cast<std::size_t>(w));
}

}  // namespace
}  // namespace lasercell::triangulation
