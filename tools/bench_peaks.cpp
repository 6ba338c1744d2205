// `lasercell bench peaks`: accuracy of the laser peak estimators (triangulation/
// peak_detection.hpp) over the signal-to-noise ratio, on raw laser-line images rendered by the
// simulator (datasets::ImageRenderer::RenderLaserLine) for each stripe shape of
// datasets::StripeShapePreset: the point-sampled Gaussian (on which the Gaussian three-point
// estimator is exact by construction), the Gaussian integrated over each pixel, an asymmetric
// stripe (half-Gaussians of 0.7 s and 1.3 s), speckle (contrast 0.25, grain 1.5 px) and a
// saturated stripe clipped at 255. Ambient offset, Gaussian read noise, 8-bit quantization.
// SNR = stripe amplitude (peak of the noise-free profile above the ambient, before clipping) /
// read-noise sigma (gray levels); the saturated shape runs over-exposure factors instead,
// amplitude = factor * (255 - ambient). Rows cover every subpixel phase (golden-ratio
// sequence). Per estimator: detection rate, columns the detector flags saturated, outliers
// (|error| > 1 px: a noise sample taken for the stripe), then over the inliers: bias (mean
// error), sigma, the systematic subpixel error (largest |mean error| over 10 phase bins: the
// S-curve; on a biased shape it includes the bias), and the Cramer-Rao bound of the shape.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "datasets/camera_images.hpp"
#include "tools/bench.hpp"
#include "triangulation/peak_detection.hpp"

namespace lasercell::tools {
namespace {

constexpr double kFwhmToSigma = 1.0 / 2.3548200450309493;
constexpr double kAmbient = 6.0;  // ImageRenderOptions default, gray levels

struct PeaksBenchArgs {
  std::vector<double> snr = {3, 5, 10, 20, 50, 100, 150};
  std::vector<double> overexposure = {1.25, 2, 4, 8};  // saturated: peak / (255 - ambient)
  std::string shape = "all";
  double width_px = 3.0;  // stripe FWHM
  double noise = 1.5;     // read noise, gray levels
  int images = 4;         // 1024 columns each
  unsigned seed = 1;
  std::string json_out;
};

struct Stats {
  int total = 0, detected = 0, outliers = 0, saturated = 0;
  double sum = 0, sum2 = 0;
  double bin_sum[10] = {};
  int bin_n[10] = {};
};

constexpr triangulation::PeakEstimator kEstimators[] = {
    triangulation::PeakEstimator::kCenterOfGravity, triangulation::PeakEstimator::kGaussian,
    triangulation::PeakEstimator::kBlaisRioux};

std::string Describe(const std::string& name) {
  if (name == "sampled-gaussian") return "Gaussian sampled at the pixel centres (as before)";
  if (name == "pixel-area") return "Gaussian averaged over each pixel's extent (erf)";
  if (name == "asymmetric") {
    return "half-Gaussians of 0.7 s above and 1.3 s below the true row (the mode), "
           "pixel-averaged; centroid 0.61 px below the mode";
  }
  if (name == "speckle") {
    return "pixel-averaged Gaussian x log-normal speckle (contrast 0.25, grain 1.5 px along the "
           "column, fresh per column)";
  }
  return "pixel-averaged Gaussian over-exposed: amplitude = factor x (255 - ambient), top clipped "
         "at 255; SNR = unclipped amplitude / read noise";
}

// Fisher information of one sample of mean mu (absolute gray level) about mu, white noise
// sigma_n, censored at 254.5 (the sample reads 255 above it; Tobit model):
// (Phi(z) - z phi(z) + phi(z)^2 / (1 - Phi(z))) / sigma_n^2, z = (254.5 - mu) / sigma_n.
double CensoredInformation(double mu, double sigma_n) {
  const double z = (254.5 - mu) / sigma_n;
  if (z > 30) return 1.0 / (sigma_n * sigma_n);
  const double phi = std::exp(-0.5 * z * z) / std::sqrt(2 * std::numbers::pi);
  const double cdf = 0.5 * std::erfc(-z / std::numbers::sqrt2);
  const double tail = 0.5 * std::erfc(z / std::numbers::sqrt2);
  const double censored = tail > 0 ? phi * phi / tail : 0.0;
  return std::max(0.0, cdf - z * phi + censored) / (sigma_n * sigma_n);
}

// Cramer-Rao bound on the row for the shape's noise-free profile (amplitude, width and
// background known; read noise sigma_n white; clipping at 255 as censoring; speckle ignored:
// it only adds error), as the RMS over subpixel phases: sqrt(mean over phases of 1 / I(phase)),
// I = sum_y I_mu(mu_y) (d mu_y / d row)^2. For the unclipped sampled Gaussian this is
// sigma_n / A sqrt(2 s / sqrt(pi)) (Poisson summation: the sum equals the integral to 1e-7).
double ShapeCrb(const datasets::StripeShape& shape, double amplitude, double s, double sigma_n) {
  const double s_lo = (1 - shape.asymmetry) * s, s_hi = (1 + shape.asymmetry) * s;
  const auto f = [&](double t) {  // profile of peak 1, t = row offset from the mode
    const double d = t / (t < 0 ? s_lo : s_hi);
    return std::exp(-0.5 * d * d);
  };
  const auto cdf = [&](double t) {  // its integral from -inf (camera_images.cpp)
    constexpr double kSqrtHalfPi = 1.2533141373155003;
    if (t < 0) return kSqrtHalfPi * s_lo * std::erfc(-t / (std::numbers::sqrt2 * s_lo));
    return kSqrtHalfPi * (s_lo + s_hi * std::erf(t / (std::numbers::sqrt2 * s_hi)));
  };
  const int reach = static_cast<int>(std::ceil(6 * std::max(s_lo, s_hi))) + 2;
  const int phases = 32;
  double mean_inverse = 0;
  for (int p = 0; p < phases; ++p) {
    const double row = (p + 0.5) / phases;
    double info = 0;
    for (int y = -reach; y <= reach; ++y) {
      const double t = y - row;
      double mu, dmu;
      if (shape.integrate_pixel_area) {
        mu = amplitude * (cdf(t + 0.5) - cdf(t - 0.5));
        dmu = amplitude * (f(t - 0.5) - f(t + 0.5));
      } else {
        const double st = t < 0 ? s_lo : s_hi;
        mu = amplitude * f(t);
        dmu = mu * t / (st * st);
      }
      info += CensoredInformation(kAmbient + mu, sigma_n) * dmu * dmu;
    }
    mean_inverse += 1.0 / info / phases;
  }
  return std::sqrt(mean_inverse);
}

// Renders args.images images of the shape at one amplitude and scores the three estimators;
// `level` (the SNR or over-exposure factor) seeds the noise, as before the shapes existed.
std::vector<Stats> ScoreShape(const PeaksBenchArgs& args, const datasets::ImageRenderer& renderer,
                              const datasets::StripeShape& shape, double level, double amplitude) {
  const int w = renderer.camera().width_px();
  std::vector<Stats> stats(3);
  for (int image = 0; image < args.images; ++image) {
    datasets::ExposureTruth ex;
    ex.row_px.resize(w);
    ex.intensity.assign(w, amplitude / (255.0 * shape.peak_gain));
    ex.width_px.assign(w, args.width_px);
    for (int u = 0; u < w; ++u) {
      ex.row_px[u] = 200.0 + 0.5 * u + std::fmod(0.6180339887498949 * (u + w * image), 1.0);
    }
    datasets::ImageRenderOptions io;
    io.noise_sigma = args.noise;
    const Image8 img = renderer.RenderLaserLine(
        ex, io, shape,
        args.seed * 1000003ULL + image * 7919ULL + static_cast<std::uint64_t>(level * 1000));
    for (int e = 0; e < 3; ++e) {
      triangulation::PeakDetectionOptions o;
      o.estimator = kEstimators[e];
      o.min_height = 3 * args.noise;
      const auto r = triangulation::DetectPeaks(
          triangulation::ImageView8{img.pixels.data(), img.width, img.height, 0}, o);
      Stats& st = stats[e];
      st.saturated += static_cast<int>(r.saturated);
      for (int u = 0; u < w; ++u) {
        ++st.total;
        const double row = r.profile.row_px[u];
        if (std::isnan(row)) continue;
        ++st.detected;
        const double err = row - ex.row_px[u];
        if (std::abs(err) > 1.0) {
          ++st.outliers;
          continue;
        }
        st.sum += err;
        st.sum2 += err * err;
        const double phase = ex.row_px[u] - std::floor(ex.row_px[u]);
        const int bin = std::min(9, static_cast<int>(phase * 10));
        st.bin_sum[bin] += err;
        ++st.bin_n[bin];
      }
    }
  }
  return stats;
}

// One table block: every amplitude of the shape, three estimators each. Returns its JSON rows.
nlohmann::json RunShape(const PeaksBenchArgs& args, const datasets::ImageRenderer& renderer,
                        const std::string& name) {
  const datasets::StripeShape shape = datasets::StripeShapePreset(name);
  const bool saturated = name == "saturated";
  const double s = args.width_px * kFwhmToSigma;
  const double sigma_n = std::sqrt(args.noise * args.noise + 1.0 / 12);  // + quantization
  std::printf("#### %s: %s\n\n", name.c_str(), Describe(name).c_str());
  std::printf(
      "| SNR | amplitude | estimator | detected | flagged saturated | outliers | bias px | "
      "sigma px | S-curve px | CRB px |\n|---|---|---|---|---|---|---|---|---|---|\n");
  nlohmann::json rows = nlohmann::json::array();
  for (const double level : saturated ? args.overexposure : args.snr) {
    const double amplitude = saturated ? level * (255 - kAmbient) : level * args.noise;
    const std::vector<Stats> stats = ScoreShape(args, renderer, shape, level, amplitude);
    const double crb = ShapeCrb(shape, amplitude, s, sigma_n);
    for (int e = 0; e < 3; ++e) {
      const Stats& st = stats[e];
      const int n = st.detected - st.outliers;
      const double mean = n > 0 ? st.sum / n : NAN;
      const double sigma = n > 1 ? std::sqrt(std::max(0.0, st.sum2 / n - mean * mean)) : NAN;
      double scurve = 0;
      for (int b = 0; b < 10; ++b) {
        if (st.bin_n[b] > 0) scurve = std::max(scurve, std::abs(st.bin_sum[b] / st.bin_n[b]));
      }
      const double detected = 100.0 * st.detected / st.total;
      const double flagged = 100.0 * st.saturated / st.total;
      const double outliers = st.detected ? 100.0 * st.outliers / st.detected : 0.0;
      const std::string estimator = triangulation::PeakEstimatorName(kEstimators[e]);
      std::printf("| %g | %.1f | %s | %.1f %% | %.1f %% | %.2f %% | %+.4f | %.4f | %.4f | %.4f |\n",
                  amplitude / args.noise, amplitude, estimator.c_str(), detected, flagged, outliers,
                  mean, sigma, scurve, crb);
      rows.push_back({{"shape", name},
                      {"snr", amplitude / args.noise},
                      {"amplitude", amplitude},
                      {"estimator", estimator},
                      {"detected_percent", detected},
                      {"flagged_saturated_percent", flagged},
                      {"outliers_percent", outliers},
                      {"inliers", n},
                      {"bias_px", std::isfinite(mean) ? nlohmann::json(mean) : nlohmann::json()},
                      {"sigma_px", std::isfinite(sigma) ? nlohmann::json(sigma) : nlohmann::json()},
                      {"scurve_px", scurve},
                      {"crb_px", crb}});
    }
  }
  std::printf("\n");
  return rows;
}

void RunPeaksBench(const PeaksBenchArgs& args) {
  if (args.width_px < 1 || args.width_px > 20) throw OptionError("--width-px must be in [1, 20]");
  for (const double snr : args.snr) {
    if (snr * args.noise > 255 - kAmbient) {
      throw OptionError("--snr values must keep the stripe below saturation (amplitude <= 249)");
    }
  }
  const std::vector<std::string> names = args.shape == "all" ? datasets::StripeShapePresetNames()
                                                             : std::vector<std::string>{args.shape};
  for (const std::string& name : names) datasets::StripeShapePreset(name);  // --shape is valid
  const datasets::ImageRenderer renderer{datasets::MakeCameraModel()};
  std::printf(
      "lasercell bench peaks: %d images x %d columns per SNR, stripe FWHM %.2f px, read noise "
      "%.2f gray levels (8-bit, ambient %g), min_height 3 sigma; errors in px vs the exact "
      "row (the beam centre = the profile's mode)\n\n",
      args.images, renderer.camera().width_px(), args.width_px, args.noise, kAmbient);
  nlohmann::json rows = nlohmann::json::array();
  for (const std::string& name : names) {
    for (nlohmann::json& row : RunShape(args, renderer, name)) rows.push_back(std::move(row));
  }
  std::printf(
      "S-curve: largest |mean error| over 10 subpixel-phase bins (systematic part; it includes "
      "the bias and sigma / sqrt(n per bin) of noise). flagged saturated: columns the detector "
      "reports as saturated (their row is the centre of gravity of the clipped plateau whatever "
      "the estimator). CRB: Cramer-Rao bound on the row for the shape's noise-free profile "
      "(amplitude, width, background known; read + quantization noise white; clipping as "
      "censoring; speckle not included), RMS over subpixel phases: no unbiased estimator can "
      "have a lower sigma.\n");
  if (!args.json_out.empty()) {
    nlohmann::json j = {{"format", "lasercell.bench_peaks"},
                        {"version", 1},
                        {"width_px", args.width_px},
                        {"noise", args.noise},
                        {"images", args.images},
                        {"columns", renderer.camera().width_px()},
                        {"seed", args.seed},
                        {"rows", rows}};
    io::WriteFileAtomically(args.json_out, j.dump(2) + "\n");
  }
}

}  // namespace

void AddBenchPeaksCommand(CLI::App& bench) {
  CLI::App* cmd = bench.add_subcommand(
      "peaks",
      "Laser peak estimators (centre of gravity, Gaussian, Blais-Rioux): bias and sigma "
      "over SNR on simulated stripe images of several shapes");
  auto args = std::make_shared<PeaksBenchArgs>();
  cmd->add_option("--shape", args->shape,
                  "Stripe shape: all, sampled-gaussian, pixel-area, asymmetric, speckle, "
                  "saturated (one table block each)")
      ->capture_default_str();
  cmd->add_option("--snr", args->snr, "Stripe amplitude / read noise, per table row")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--overexposure", args->overexposure,
                  "Saturated shape: amplitude / (255 - ambient), per table row")
      ->delimiter(',')
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--width-px", args->width_px, "Stripe FWHM, px")->capture_default_str();
  cmd->add_option("--noise", args->noise, "Read noise sigma, gray levels")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--images", args->images, "Images (1024 columns each) per SNR")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Noise seed")->capture_default_str();
  cmd->add_option("--json", args->json_out, "Also write every row as JSON");
  cmd->callback([args] { RunPeaksBench(*args); });
}

}  // namespace lasercell::tools
