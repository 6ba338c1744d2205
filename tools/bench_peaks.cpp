// `lasercell bench peaks`: accuracy of the laser peak estimators (triangulation/
// peak_detection.hpp) over the signal-to-noise ratio, on raw laser-line images rendered by the
// simulator (datasets::ImageRenderer::RenderLaserLine: a point-sampled Gaussian stripe per
// column at an exact row, ambient offset, Gaussian read noise, 8-bit quantization).
// SNR = stripe amplitude / read-noise sigma (gray levels). Rows cover every subpixel phase
// (golden-ratio sequence). Per estimator: detection rate, outliers (|error| > 1 px: a noise
// sample taken for the stripe), then over the inliers: bias (mean error), sigma, the
// systematic subpixel error (largest |mean error| over 10 phase bins: the S-curve), and the
// Cramer-Rao bound of a Gaussian peak in white noise, sigma_n / A * sqrt(2 s / sqrt(pi)).
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "datasets/camera_images.hpp"
#include "tools/bench.hpp"
#include "triangulation/peak_detection.hpp"

namespace lasercell::tools {
namespace {

struct PeaksBenchArgs {
  std::vector<double> snr = {3, 5, 10, 20, 50, 100, 150};
  double width_px = 3.0;  // stripe FWHM
  double noise = 1.5;     // read noise, gray levels
  int images = 4;         // 1024 columns each
  unsigned seed = 1;
};

struct Stats {
  int total = 0, detected = 0, outliers = 0;
  double sum = 0, sum2 = 0;
  double bin_sum[10] = {};
  int bin_n[10] = {};
};

void RunPeaksBench(const PeaksBenchArgs& args) {
  if (args.width_px < 1 || args.width_px > 20) throw OptionError("--width-px must be in [1, 20]");
  const datasets::ImageRenderer renderer{datasets::MakeCameraModel()};
  const int w = 1024;
  const double s = args.width_px / 2.3548200450309493;
  const double sigma_n = std::sqrt(args.noise * args.noise + 1.0 / 12);  // + quantization
  const triangulation::PeakEstimator estimators[] = {triangulation::PeakEstimator::kCenterOfGravity,
                                                     triangulation::PeakEstimator::kGaussian,
                                                     triangulation::PeakEstimator::kBlaisRioux};
  std::printf(
      "lasercell bench peaks: %d images x %d columns per SNR, stripe FWHM %.2f px, read noise "
      "%.2f gray levels (8-bit, ambient 6), min_height 3 sigma; errors in px vs the exact "
      "rendered row\n\n",
      args.images, w, args.width_px, args.noise);
  std::printf(
      "| SNR | amplitude | estimator | detected | outliers | bias px | sigma px | S-curve px | "
      "CRB px |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const double snr : args.snr) {
    const double amplitude = snr * args.noise;
    if (amplitude > 249) throw OptionError("--snr values must keep the stripe below saturation");
    Stats stats[3];
    for (int image = 0; image < args.images; ++image) {
      datasets::ExposureTruth ex;
      ex.row_px.resize(w);
      ex.intensity.assign(w, amplitude / 255.0);
      ex.width_px.assign(w, args.width_px);
      for (int u = 0; u < w; ++u) {
        ex.row_px[u] = 200.0 + 0.5 * u + std::fmod(0.6180339887498949 * (u + w * image), 1.0);
      }
      datasets::ImageRenderOptions io;
      io.noise_sigma = args.noise;
      const Image8 img = renderer.RenderLaserLine(
          ex, io,
          args.seed * 1000003ULL + image * 7919ULL + static_cast<std::uint64_t>(snr * 1000));
      for (int e = 0; e < 3; ++e) {
        triangulation::PeakDetectionOptions o;
        o.estimator = estimators[e];
        o.min_height = 3 * args.noise;
        const auto r = triangulation::DetectPeaks(
            triangulation::ImageView8{img.pixels.data(), img.width, img.height, 0}, o);
        Stats& st = stats[e];
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
    const double crb = sigma_n / amplitude * std::sqrt(2 * s / std::sqrt(std::numbers::pi));
    for (int e = 0; e < 3; ++e) {
      const Stats& st = stats[e];
      const int n = st.detected - st.outliers;
      const double mean = n > 0 ? st.sum / n : NAN;
      const double sigma = n > 1 ? std::sqrt(std::max(0.0, st.sum2 / n - mean * mean)) : NAN;
      double scurve = 0;
      for (int b = 0; b < 10; ++b) {
        if (st.bin_n[b] > 0) scurve = std::max(scurve, std::abs(st.bin_sum[b] / st.bin_n[b]));
      }
      std::printf("| %g | %.1f | %s | %.1f %% | %.2f %% | %+.4f | %.4f | %.4f | %.4f |\n", snr,
                  amplitude, triangulation::PeakEstimatorName(estimators[e]).c_str(),
                  100.0 * st.detected / st.total,
                  st.detected ? 100.0 * st.outliers / st.detected : 0.0, mean, sigma, scurve, crb);
    }
  }
  std::printf(
      "\nS-curve: largest |mean error| over 10 subpixel-phase bins (systematic part; it includes "
      "sigma / sqrt(n per bin) of noise). CRB: Cramer-Rao bound for the row of a sampled Gaussian "
      "in white noise (no estimator can have a lower sigma).\n");
}

}  // namespace

void AddBenchPeaksCommand(CLI::App& bench) {
  CLI::App* cmd = bench.add_subcommand(
      "peaks",
      "Laser peak estimators (centre of gravity, Gaussian, Blais-Rioux): bias and sigma "
      "over SNR on simulated stripe images");
  auto args = std::make_shared<PeaksBenchArgs>();
  cmd->add_option("--snr", args->snr, "Stripe amplitude / read noise, per table block")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--width-px", args->width_px, "Stripe FWHM, px")->capture_default_str();
  cmd->add_option("--noise", args->noise, "Read noise sigma, gray levels")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--images", args->images, "Images (1024 columns each) per SNR")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Noise seed")->capture_default_str();
  cmd->callback([args] { RunPeaksBench(*args); });
}

}  // namespace lasercell::tools
