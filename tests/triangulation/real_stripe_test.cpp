// Peak detection on real laser-stripe images (laser_stripe_chessboard of the shared development
// data, read from ../shared/data or $LASERCELL_SHARED_DATA: no licence stated, so the images are
// not bundled and the tests skip with a message when the set is absent; a green line across a
// planar chessboard, 640 x 480 JPEG). The stripe is vertical (it crosses every image
// row), so the detector runs with peaks_per_row: profile column k = image row k, peak "row" =
// image column. The laser
// signal is green minus red (the white and grey board reflect both; the 532 nm line only green).
// No ground truth: what must hold is geometry. The laser plane meets the planar board in a 3D
// line, which the lens (k1 = -0.35, strong barrel distortion) maps to a smooth curve; so on the
// board the peaks must form one connected, smooth curve (a low-order polynomial in the row fits
// it to a fraction of a pixel), and the three estimators must agree on it.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "tests/shared_data.hpp"
#include "triangulation/peak_detection.hpp"

namespace lasercell::triangulation {
namespace {

const char kSet[] = "laser_stripe_chessboard";

// Skips the calling test (with the reason) when the shared set is absent.
#define REQUIRE_STRIPE_IMAGES()                                                    \
  if (lasercell::shared_data::SharedDataSet(kSet).empty()) {                       \
    LASERCELL_SHARED_DATA_ABSENT(lasercell::shared_data::SharedDataMissing(kSet)); \
  }

// Green minus red (640 x 480, 8-bit).
std::vector<std::uint8_t> StripeSignal(const std::string& file, int* w, int* h) {
  const cv::Mat bgr =
      cv::imread(lasercell::shared_data::SharedDataSet(kSet) + "/" + file, cv::IMREAD_COLOR);
  EXPECT_FALSE(bgr.empty()) << file;
  *w = bgr.cols;
  *h = bgr.rows;
  std::vector<std::uint8_t> out(static_cast<std::size_t>(bgr.rows) * bgr.cols);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      out[static_cast<std::size_t>(y) * bgr.cols + x] =
          static_cast<std::uint8_t>(std::max(0, int(p[1]) - int(p[2])));
    }
  }
  return out;
}

// Residual RMS and max of a least-squares polynomial (in normalized row) through (k, x_k).
void PolyFit(const std::vector<double>& k, const std::vector<double>& x, int degree, double* rms,
             double* worst) {
  const double c = 0.5 * (k.front() + k.back()), s = 0.5 * (k.back() - k.front());
  Eigen::MatrixXd a(k.size(), degree + 1);
  Eigen::VectorXd b(k.size());
  for (std::size_t i = 0; i < k.size(); ++i) {
    double t = (k[i] - c) / s, p = 1;
    for (int d = 0; d <= degree; ++d, p *= t) a(i, d) = p;
    b[i] = x[i];
  }
  const Eigen::VectorXd coef = a.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd r = a * coef - b;
  *rms = std::sqrt(r.squaredNorm() / r.size());
  *worst = r.cwiseAbs().maxCoeff();
}

struct Case {
  std::string file;
  int board_first_row, board_last_row;  // image rows where the stripe crosses the board (by eye)
};
// 1_right: board from row ~95 to ~455; 4_right: ~88 to ~368, then the floor.
const Case kCases[] = {{"1_right.jpg", 100, 450}, {"4_right.jpg", 95, 360}};

PeakDetectionResult Detect(const Case& c, PeakEstimator estimator) {
  int w = 0, h = 0;
  const auto img = StripeSignal(c.file, &w, &h);
  PeakDetectionOptions o;
  o.estimator = estimator;
  o.peaks_per_row = true;  // the line is vertical in these images
  return DetectPeaks(ImageView8{img.data(), w, h, 0}, o);
}

// On the board the stripe is found in (nearly) every row, unsaturated, and its peaks form one
// smooth curve: a quadratic in the row (the line through barrel distortion over a ~1/2-image
// span) leaves sub-pixel residuals; a detector that jumps between the stripe and the checker
// edges or JPEG blocks would leave pixel-sized ones.
TEST(RealStripe, PeaksFollowOneSmoothCurveAcrossTheBoard) {
  REQUIRE_STRIPE_IMAGES();
  for (const Case& c : kCases) {
    const PeakDetectionResult r = Detect(c, PeakEstimator::kGaussian);
    ASSERT_EQ(r.status.size(), 480u);
    std::vector<double> k, x;
    int saturated = 0;
    for (int row = c.board_first_row; row <= c.board_last_row; ++row) {
      saturated += r.status[row] == PeakStatus::kSaturated ? 1 : 0;
      if (std::isnan(r.profile.row_px[row])) continue;
      k.push_back(row);
      x.push_back(r.profile.row_px[row]);
    }
    const int rows = c.board_last_row - c.board_first_row + 1;
    EXPECT_GE(k.size(), 0.97 * rows) << c.file << ": " << r.Summary();
    EXPECT_EQ(saturated, 0) << c.file;
    double rms = 0, worst = 0;
    PolyFit(k, x, 2, &rms, &worst);
    std::printf("%s: %zu of %d board rows, quadratic fit rms %.3f px, max %.3f px; %s\n",
                c.file.c_str(), k.size(), rows, rms, worst, r.Summary().c_str());
    EXPECT_LT(rms, 0.4) << c.file;
    EXPECT_LT(worst, 1.5) << c.file;
    // The stripe's image column on the board: left of the image centre, as seen.
    for (double v : x) {
      EXPECT_GT(v, 280.0);
      EXPECT_LT(v, 310.0);
    }
  }
}

// Below the board the line continues on the floor: a different plane, so the curve has a kink
// at the board's lower edge (piecewise linear). 4_right.jpg: slope on the board vs the floor.
TEST(RealStripe, TheLineBendsWhereItLeavesTheBoard) {
  REQUIRE_STRIPE_IMAGES();
  const PeakDetectionResult r = Detect(kCases[1], PeakEstimator::kGaussian);
  const auto slope = [&](int first, int last) {
    std::vector<double> k, x;
    for (int row = first; row <= last; ++row) {
      if (std::isnan(r.profile.row_px[row])) continue;
      k.push_back(row);
      x.push_back(r.profile.row_px[row]);
    }
    Eigen::MatrixXd a(k.size(), 2);
    Eigen::VectorXd b(k.size());
    for (std::size_t i = 0; i < k.size(); ++i) {
      a(i, 0) = 1;
      a(i, 1) = k[i];
      b[i] = x[i];
    }
    return a.colPivHouseholderQr().solve(b)[1];
  };
  const double board = slope(200, 360), floor = slope(385, 470);
  std::printf("4_right.jpg: slope on the board %.4f px/row, on the floor %.4f px/row\n", board,
              floor);
  EXPECT_GT(std::abs(floor - board), 0.04);  // ~4x the board's slope
  EXPECT_LT(std::abs(board), 0.05);
}

// The estimators see the same stripe: on the board their rows agree to a fraction of a pixel.
TEST(RealStripe, EstimatorsAgreeOnTheBoard) {
  REQUIRE_STRIPE_IMAGES();
  for (const Case& c : kCases) {
    const PeakDetectionResult g = Detect(c, PeakEstimator::kGaussian);
    for (const PeakEstimator e : {PeakEstimator::kCenterOfGravity, PeakEstimator::kBlaisRioux}) {
      const PeakDetectionResult o = Detect(c, e);
      double sum2 = 0;
      int n = 0;
      for (int row = c.board_first_row; row <= c.board_last_row; ++row) {
        if (std::isnan(g.profile.row_px[row]) || std::isnan(o.profile.row_px[row])) continue;
        const double d = g.profile.row_px[row] - o.profile.row_px[row];
        sum2 += d * d;
        ++n;
      }
      ASSERT_GT(n, 200);
      const double rms = std::sqrt(sum2 / n);
      std::printf("%s: gaussian vs %s rms %.3f px\n", c.file.c_str(), PeakEstimatorName(e).c_str(),
                  rms);
      EXPECT_LT(rms, 0.35) << c.file << " " << PeakEstimatorName(e);
    }
  }
}

}  // namespace
}  // namespace lasercell::triangulation
