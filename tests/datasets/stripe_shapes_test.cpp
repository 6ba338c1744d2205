// Stripe shapes of ImageRenderer::RenderLaserLine (datasets/camera_images.hpp, StripeShape):
// each preset checked against an independent closed form of what it claims to render.
// Simulation profile: ideal photometry (ImageRenderOptions{}), mostly with the read noise off;
// the stripe shapes are not part of either profile.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "datasets/camera_images.hpp"
#include "datasets/rng.hpp"
#include "datasets/sensor.hpp"

namespace lasercell::datasets {
namespace {

constexpr double kFwhmToSigma = 1.0 / 2.3548200450309493;
constexpr double kGolden = 0.6180339887498949;

const ImageRenderer& Renderer() {
  static const ImageRenderer renderer{MakeCameraModel()};
  return renderer;
}

// One stripe per column, rows at every subpixel phase (golden-ratio sequence) around row0.
ExposureTruth Stripes(double intensity, double width_px, double row0, int image = 0) {
  const int w = Renderer().camera().width_px();
  ExposureTruth ex;
  ex.row_px.resize(w);
  ex.intensity.assign(w, intensity);
  ex.width_px.assign(w, width_px);
  for (int u = 0; u < w; ++u) {
    ex.row_px[u] = row0 + 0.25 * u + std::fmod(kGolden * (u + w * image), 1.0);
  }
  return ex;
}

ImageRenderOptions NoiseFree() {
  ImageRenderOptions io;
  io.noise_sigma = 0;
  return io;
}

double Phi(double z) { return 0.5 * std::erfc(-z / std::numbers::sqrt2); }

// Today's RenderLaserLine, written out independently: a point-sampled Gaussian per column within
// 5 sigma, ghosts of FWHM 2 px, float accumulation over the ambient, then read noise from
// Rng(seed) in pixel order, rounding and clipping.
Image8 PointSampledReference(const ExposureTruth& ex, const ImageRenderOptions& io,
                             std::uint64_t seed) {
  const int w = Renderer().camera().width_px(), h = Renderer().camera().height_px();
  std::vector<float> img(static_cast<std::size_t>(w) * h, static_cast<float>(io.ambient));
  const auto add = [&](int x, double row, double width, double intensity) {
    const double sigma = width / 2.3548200450309493;
    const double peak = 255.0 * intensity;
    const int y0 = std::max(0, static_cast<int>(std::floor(row - 5 * sigma)));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(row + 5 * sigma)));
    for (int y = y0; y <= y1; ++y) {
      const double d = (y - row) / sigma;
      img[static_cast<std::size_t>(y) * w + x] += static_cast<float>(peak * std::exp(-0.5 * d * d));
    }
  };
  for (int x = 0; x < w; ++x) {
    if (!std::isnan(ex.row_px[x])) add(x, ex.row_px[x], ex.width_px[x], ex.intensity[x]);
    if (!ex.reflection_row_px.empty() && !std::isnan(ex.reflection_row_px[x])) {
      add(x, ex.reflection_row_px[x], 2.0, ex.reflection_intensity[x]);
    }
  }
  Image8 out;
  out.width = w;
  out.height = h;
  out.pixels.resize(img.size());
  Rng rng(seed);
  for (std::size_t i = 0; i < img.size(); ++i) {
    const double v = img[i] + (io.noise_sigma > 0 ? io.noise_sigma * rng.Normal() : 0.0);
    out.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  }
  return out;
}

TEST(StripeShapes, DefaultShapeIsTodaysPointSampledGaussianByteForByte) {
  ExposureTruth ex = Stripes(0.5, 3.0, 200.0);
  const int w = static_cast<int>(ex.row_px.size());
  ex.reflection_row_px.assign(w, NAN);
  ex.reflection_intensity.assign(w, 0.0);
  for (int u = 0; u < w; ++u) {
    ex.intensity[u] = 0.1 + 0.8 * std::fmod(0.37 * u, 1.0);
    ex.width_px[u] = 2.0 + 4.0 * std::fmod(0.71 * u, 1.0);
    if (u % 9 == 0) ex.row_px[u] = NAN;
    if (u % 5 == 0) {
      ex.reflection_row_px[u] = 700.0 + 0.3 * u;
      ex.reflection_intensity[u] = 0.2;
    }
  }
  const ImageRenderOptions io;  // read noise 1.5
  const Image8 reference = PointSampledReference(ex, io, 17);
  EXPECT_EQ(Renderer().RenderLaserLine(ex, io, 17).pixels, reference.pixels);
  EXPECT_EQ(Renderer().RenderLaserLine(ex, io, StripeShape{}, 17).pixels, reference.pixels);
  EXPECT_EQ(Renderer().RenderLaserLine(ex, io, StripeShapePreset("sampled-gaussian"), 17).pixels,
            reference.pixels);
  // The comparison can tell shapes apart: pixel-area integration changes the image.
  EXPECT_NE(Renderer().RenderLaserLine(ex, io, StripeShapePreset("pixel-area"), 17).pixels,
            reference.pixels);
}

TEST(StripeShapes, PixelAreaStripeHoldsEachPixelsMeanIrradiance) {
  const double amplitude = 204.0, width = 3.0, s = width * kFwhmToSigma;
  const ExposureTruth ex = Stripes(amplitude / 255.0, width, 300.0);
  const ImageRenderOptions io = NoiseFree();
  const Image8 area = Renderer().RenderLaserLine(ex, io, StripeShapePreset("pixel-area"), 1);
  const Image8 point = Renderer().RenderLaserLine(ex, io, 1);
  double largest_point_difference = 0;
  for (int x = 0; x < area.width; x += 3) {
    const double r = ex.row_px[x];
    for (int y = static_cast<int>(r) - 8; y <= static_cast<int>(r) + 8; ++y) {
      // Mean of A exp(-t^2 / 2 s^2) over [y - 1/2, y + 1/2].
      const double mean = amplitude * s * std::sqrt(2 * std::numbers::pi) *
                          (Phi((y + 0.5 - r) / s) - Phi((y - 0.5 - r) / s));
      ASSERT_NEAR(area.at(x, y), io.ambient + mean, 0.5 + 1e-6) << "column " << x << " row " << y;
      largest_point_difference =
          std::max(largest_point_difference, std::abs(point.at(x, y) - io.ambient - mean));
    }
  }
  // Point sampling differs by several gray levels at the top (A (1 - 0.974) at phase 0).
  EXPECT_GT(largest_point_difference, 3.0);
}

TEST(StripeShapes, PixelAreaColumnSumIsTheAnalyticIntegral) {
  for (const double width : {2.0, 3.0, 6.0}) {
    const double amplitude = 180.0, s = width * kFwhmToSigma;
    const double integral = amplitude * s * std::sqrt(2 * std::numbers::pi);
    const ExposureTruth ex = Stripes(amplitude / 255.0, width, 300.0);
    const ImageRenderOptions io = NoiseFree();
    const Image8 img = Renderer().RenderLaserLine(ex, io, StripeShapePreset("pixel-area"), 3);
    for (int x = 0; x < img.width; ++x) {
      double sum = 0;
      int lit = 0;
      for (int y = 250; y < 700; ++y) {
        sum += img.at(x, y) - io.ambient;
        lit += img.at(x, y) > io.ambient;
      }
      // Each lit pixel is rounded by <= 1/2; the unlit tail (values < 1/2 each, rounded to 0)
      // holds < 1/2 gray level in all at these amplitudes (A s sqrt(2 pi) * 2 (1 - Phi(3.4))).
      ASSERT_NEAR(sum, integral, 0.5 * lit + 0.5) << "width " << width << " column " << x;
    }
  }
}

TEST(StripeShapes, AsymmetricStripeHasItsModeAtTheTrueRowAndItsCentroidOnTheWideSide) {
  const double amplitude = 204.0, width = 3.0, s = width * kFwhmToSigma;
  const StripeShape preset = StripeShapePreset("asymmetric");
  ASSERT_DOUBLE_EQ(preset.asymmetry, 0.3);
  const double s_lo = 0.7 * s, s_hi = 1.3 * s;
  const ExposureTruth ex = Stripes(amplitude / 255.0, width, 300.0);
  const ImageRenderOptions io = NoiseFree();
  // Mode: point-sampled, each side is the half-Gaussian of its own width peaking at the true
  // row: invert one sample 1-2 rows away on each side, r = y -+ s_side sqrt(2 ln(A / v)).
  // Rounding v by 1/2 moves that by s_side^2 / (|y - r| v) / 2.
  StripeShape sampled = preset;
  sampled.integrate_pixel_area = false;
  const Image8 point = Renderer().RenderLaserLine(ex, io, sampled, 2);
  const auto row_from = [&](int x, int y, double s_side, double sign) {
    const double v = point.at(x, y) - io.ambient;
    const double d = s_side * std::sqrt(2 * std::log(amplitude / v));
    return std::pair(y + sign * d, 0.5 * s_side * s_side / (d * v) + 1e-6);
  };
  for (int x = 0; x < point.width; x += 5) {
    const double r = ex.row_px[x];
    const auto [from_above, tol_above] = row_from(x, static_cast<int>(std::floor(r)) - 1, s_lo, 1);
    const auto [from_below, tol_below] = row_from(x, static_cast<int>(std::ceil(r)) + 1, s_hi, -1);
    EXPECT_NEAR(from_above, r, tol_above) << "column " << x;
    EXPECT_NEAR(from_below, r, tol_below) << "column " << x;
  }
  // Centroid, pixel-integrated: the mean of two half-Gaussians, sqrt(2 / pi) (s_hi - s_lo) below
  // the mode (towards the wider side; the box filter keeps it to < 0.001 px over all phases).
  const double shift = std::sqrt(2 / std::numbers::pi) * (s_hi - s_lo);
  const Image8 img = Renderer().RenderLaserLine(ex, io, preset, 2);
  for (int x = 0; x < img.width; ++x) {
    const double expected = ex.row_px[x] + shift;
    double sum = 0, sum_y = 0, sum_abs = 0;
    for (int y = static_cast<int>(expected) - 12; y <= static_cast<int>(expected) + 12; ++y) {
      const double v = img.at(x, y) - io.ambient;
      sum += v;
      sum_y += v * y;
      sum_abs += std::abs(y - expected);
    }
    // Rounding each pixel by <= 1/2 moves the centroid by <= 1/2 sum |y - c| / sum v.
    ASSERT_NEAR(sum_y / sum, expected, 0.5 * sum_abs / sum + 0.001) << "column " << x;
  }
  // The brightest pixel of a stripe centred on a row is that row, the brighter neighbour below.
  ExposureTruth centred = ex;
  for (int u = 0; u < img.width; ++u) centred.row_px[u] = 300 + (u % 400);
  const Image8 c = Renderer().RenderLaserLine(centred, io, preset, 2);
  for (int x = 0; x < c.width; x += 7) {
    const int r = static_cast<int>(centred.row_px[x]);
    EXPECT_GT(c.at(x, r), c.at(x, r + 1)) << "column " << x;
    EXPECT_GT(c.at(x, r + 1), c.at(x, r - 1)) << "column " << x;
  }
}

TEST(StripeShapes, SpeckleHasTheConfiguredContrastAndGrainAndIsFreshPerColumn) {
  const StripeShape shape = StripeShapePreset("speckle");
  const double c = shape.speckle_contrast;
  ASSERT_DOUBLE_EQ(c, 0.25);
  const ImageRenderOptions io = NoiseFree();
  // Per column, speckled / clean pixel value at the brightest clean row and the row below it.
  std::vector<double> top, next;
  for (int image = 0; image < 4; ++image) {
    const ExposureTruth ex = Stripes(100.0 / 255.0, 3.0, 300.0, image);
    const Image8 speckled = Renderer().RenderLaserLine(ex, io, shape, 40 + image);
    const Image8 clean = Renderer().RenderLaserLine(ex, io, StripeShapePreset("pixel-area"), 1);
    for (int x = 0; x < clean.width; ++x) {
      const int r = static_cast<int>(std::lround(ex.row_px[x]));
      top.push_back((speckled.at(x, r) - io.ambient) / (clean.at(x, r) - io.ambient));
      next.push_back((speckled.at(x, r + 1) - io.ambient) / (clean.at(x, r + 1) - io.ambient));
    }
  }
  const auto mean_of = [](const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m += x;
    return m / v.size();
  };
  const auto correlation = [&](const std::vector<double>& a, const std::vector<double>& b) {
    const double ma = mean_of(a), mb = mean_of(b);
    double sab = 0, saa = 0, sbb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      sab += (a[i] - ma) * (b[i] - mb);
      saa += (a[i] - ma) * (a[i] - ma);
      sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / std::sqrt(saa * sbb);
  };
  const double n = static_cast<double>(top.size());
  const double mean = mean_of(top);
  double var = 0;
  for (double v : top) var += (v - mean) * (v - mean);
  const double contrast = std::sqrt(var / (n - 1)) / mean;
  // Log-normal of contrast C: kurtosis k = e^{4 q} + 2 e^{3 q} + 3 e^{2 q} - 3, q = ln(1 + C^2);
  // the sample std's standard error is std sqrt((k - 1) / (4 n)). 4 standard errors.
  const double q = std::log1p(c * c);
  const double kurtosis = std::exp(4 * q) + 2 * std::exp(3 * q) + 3 * std::exp(2 * q) - 3;
  EXPECT_NEAR(mean, 1.0, 4 * c / std::sqrt(n));
  EXPECT_NEAR(contrast, c, 4 * c * std::sqrt((kurtosis - 1) / (4 * n)));
  // Grain: the underlying Gaussian's correlation at one row is exp(-1 / (2 grain^2)); the
  // log-normal's is (e^{q rho} - 1) / (e^q - 1). Standard error of a correlation ~ (1 - r^2) /
  // sqrt(n).
  const double rho_g = std::exp(-1.0 / (2 * shape.speckle_grain_px * shape.speckle_grain_px));
  const double rho = std::expm1(q * rho_g) / std::expm1(q);
  EXPECT_NEAR(correlation(top, next), rho, 4 * (1 - rho * rho) / std::sqrt(n));
  // Fresh per column: neighbouring columns are uncorrelated.
  const std::vector<double> left(top.begin(), top.end() - 1), right(top.begin() + 1, top.end());
  EXPECT_NEAR(correlation(left, right), 0.0, 4 / std::sqrt(n));
  // Deterministic for a seed, different for another.
  const ExposureTruth ex = Stripes(100.0 / 255.0, 3.0, 300.0);
  EXPECT_EQ(Renderer().RenderLaserLine(ex, io, shape, 5).pixels,
            Renderer().RenderLaserLine(ex, io, shape, 5).pixels);
  EXPECT_NE(Renderer().RenderLaserLine(ex, io, shape, 5).pixels,
            Renderer().RenderLaserLine(ex, io, shape, 6).pixels);
}

TEST(StripeShapes, SaturatedStripeClipsAt255OverTheExpectedWidth) {
  const StripeShape shape = StripeShapePreset("saturated");
  ASSERT_DOUBLE_EQ(shape.peak_gain, 4.0);
  const double intensity = 0.5, width = 3.0, s = width * kFwhmToSigma;
  const double amplitude = 255.0 * intensity * shape.peak_gain;  // 510: 2x the 8-bit range
  const ImageRenderOptions io = NoiseFree();
  // A pixel reads 255 when ambient + its mean irradiance g(t) >= 254.5, t = offset of its centre
  // from the row; g falls off from t = 0, so the clipped centres fill |t| <= t*, width W = 2 t*.
  const auto g = [&](double t) {
    return amplitude * s * std::sqrt(2 * std::numbers::pi) *
           (Phi((t + 0.5) / s) - Phi((t - 0.5) / s));
  };
  double lo = 0, hi = 10;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (io.ambient + g(mid) >= 254.5 ? lo : hi) = mid;
  }
  const double expected_width = 2 * lo;  // 3.08 px
  const ExposureTruth ex = Stripes(intensity, width, 300.0);
  const Image8 img = Renderer().RenderLaserLine(ex, io, shape, 4);
  double mean_count = 0;
  for (int x = 0; x < img.width; ++x) {
    int count = 0, first = -1, last = -1;
    for (int y = 250; y < 650; ++y) {
      if (img.at(x, y) == 255) {
        ++count;
        if (first < 0) first = y;
        last = y;
      }
    }
    // The integers inside an interval of length W: floor(W) or ceil(W), contiguous, around r.
    ASSERT_GE(count, std::floor(expected_width)) << "column " << x;
    ASSERT_LE(count, std::ceil(expected_width)) << "column " << x;
    ASSERT_EQ(last - first + 1, count) << "column " << x;
    EXPECT_NEAR(0.5 * (first + last), ex.row_px[x], 0.5) << "column " << x;
    mean_count += count;
  }
  // Over all subpixel phases the mean count is W (golden-ratio phases: discrepancy ~ 1/width).
  EXPECT_NEAR(mean_count / img.width, expected_width, 0.02);
}

void ExpectOptionErrorNaming(const StripeShape& shape, const std::string& field) {
  try {
    shape.Check();
    ADD_FAILURE() << "no OptionError for " << field;
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("stripe." + field), std::string::npos) << e.what();
  }
}

TEST(StripeShapes, BadOptionsThrowOptionErrorNamingTheField) {
  StripeShapePreset("speckle").Check();  // the presets are valid
  const auto with = [](auto set) {
    StripeShape s;
    set(s);
    return s;
  };
  ExpectOptionErrorNaming(with([](StripeShape& s) { s.asymmetry = 0.95; }), "asymmetry");
  ExpectOptionErrorNaming(with([](StripeShape& s) { s.asymmetry = NAN; }), "asymmetry");
  ExpectOptionErrorNaming(with([](StripeShape& s) { s.speckle_contrast = -0.1; }),
                          "speckle_contrast");
  ExpectOptionErrorNaming(with([](StripeShape& s) { s.speckle_contrast = 1.5; }),
                          "speckle_contrast");
  ExpectOptionErrorNaming(with([](StripeShape& s) { s.speckle_grain_px = 0.2; }),
                          "speckle_grain_px");
  ExpectOptionErrorNaming(with([](StripeShape& s) { s.peak_gain = 0; }), "peak_gain");
  ExpectOptionErrorNaming(with([](StripeShape& s) { s.peak_gain = 1000; }), "peak_gain");
  // The renderer checks the shape.
  StripeShape bad;
  bad.peak_gain = -1;
  EXPECT_THROW(Renderer().RenderLaserLine(Stripes(0.5, 3.0, 300.0), NoiseFree(), bad, 1),
               OptionError);
  try {
    StripeShapePreset("gaussian");
    ADD_FAILURE() << "unknown preset accepted";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("pixel-area"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lasercell::datasets
