#include "calib/internal/stripe_detection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "calib/internal/board_pose.hpp"
#include "core/error.hpp"

namespace lasercell::calib::internal {

namespace {

cv::Mat Wrap(const Image8& image) {
  const int type = image.channels == 3 ? CV_8UC3 : CV_8UC1;
  return cv::Mat(image.height, image.width, type, const_cast<std::uint8_t*>(image.pixels.data()));
}

}  // namespace

cv::Mat GrayOf(const Image8& image) {
  cv::Mat wrapped = Wrap(image);
  if (image.channels == 1) return wrapped.clone();
  cv::Mat gray;
  cv::cvtColor(wrapped, gray, cv::COLOR_BGR2GRAY);
  return gray;
}

cv::Mat LaserChannel(const Image8& image, const std::string& color) {
  cv::Mat wrapped = Wrap(image);
  cv::Mat out;
  if (image.channels == 1 || color == "gray") {
    GrayOf(image).convertTo(out, CV_32F);
    return out;
  }
  std::vector<cv::Mat> bgr;
  cv::split(wrapped, bgr);
  std::vector<cv::Mat> f(3);
  for (int c = 0; c < 3; ++c) bgr[c].convertTo(f[c], CV_32F);
  // A coloured laser raises its own channel over the others; white and black squares raise or
  // lower all three alike, so the difference keeps the stripe and drops the board pattern.
  const int own = color == "red" ? 2 : 1;
  const int a = 0, b = own == 1 ? 2 : 1;
  out = f[own] - 0.5 * (f[a] + f[b]);
  return out;
}

Image8 Gray8Of(const Image8& image) {
  const cv::Mat gray = GrayOf(image);  // continuous: a clone or cvtColor's output
  Image8 out;
  out.width = gray.cols;
  out.height = gray.rows;
  out.pixels.assign(gray.data, gray.data + gray.total());
  return out;
}

Eigen::Isometry3d BoardPose(const CameraModel& camera, const std::vector<Eigen::Vector2d>& corners,
                            const BoardSpec& board, double* rms_px) {
  const std::vector<Eigen::Vector3d> object = board.Corners();
  std::vector<Eigen::Vector2d> normalized;
  for (const auto& r : camera.UnprojectMany(corners)) {
    normalized.emplace_back(r.x() / r.z(), r.y() / r.z());
  }
  const Eigen::Isometry3d pose = SolvePnPNormalised(object, normalized);
  if (rms_px != nullptr) {
    double sum = 0;
    for (std::size_t k = 0; k < corners.size(); ++k) {
      const Eigen::Vector3d p = pose * object[k];
      sum += (camera.Project(p) - corners[k]).squaredNorm();
    }
    *rms_px = std::sqrt(sum / static_cast<double>(corners.size()));
  }
  return pose;
}

std::vector<Eigen::Vector2d> StripePeaks(const cv::Mat& laser,
                                         const std::vector<cv::Point2f>& region, bool along_rows,
                                         const StripeOptions& options) {
  std::vector<Eigen::Vector2d> peaks;
  const int lines = along_rows ? laser.rows : laser.cols;
  const int length = along_rows ? laser.cols : laser.rows;
  std::vector<float> profile(static_cast<std::size_t>(length));
  std::vector<float> sorted;
  for (int line = 0; line < lines; ++line) {
    // The samples of this scan line inside the (convex) region: the span between the crossings
    // of the line with the region's edges.
    double lo_cross = std::numeric_limits<double>::infinity(), hi_cross = -lo_cross;
    const double scan = line;
    for (std::size_t e = 0; e < region.size(); ++e) {
      const cv::Point2f& a = region[e];
      const cv::Point2f& b = region[(e + 1) % region.size()];
      const double ac = along_rows ? a.y : a.x, bc = along_rows ? b.y : b.x;
      const double ak = along_rows ? a.x : a.y, bk = along_rows ? b.x : b.y;
      if ((ac - scan) * (bc - scan) > 0 || ac == bc) continue;
      const double k = ak + (bk - ak) * (scan - ac) / (bc - ac);
      lo_cross = std::min(lo_cross, k);
      hi_cross = std::max(hi_cross, k);
    }
    if (!(hi_cross > lo_cross)) continue;
    const int first = std::max(0, static_cast<int>(std::ceil(lo_cross)));
    const int last = std::min(length - 1, static_cast<int>(std::floor(hi_cross)));
    if (last - first < 4) continue;
    for (int k = first; k <= last; ++k) {
      profile[static_cast<std::size_t>(k)] =
          along_rows ? laser.at<float>(line, k) : laser.at<float>(k, line);
    }
    sorted.assign(profile.begin() + first, profile.begin() + last + 1);
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2),
                     sorted.end());
    const float background = sorted[sorted.size() / 2];
    const auto max_it = std::max_element(profile.begin() + first, profile.begin() + last + 1);
    const int kmax = static_cast<int>(max_it - profile.begin());
    const float peak = *max_it - background;
    if (peak < options.min_peak_contrast || kmax == first || kmax == last) continue;
    // The run above half maximum around the peak.
    const float half = background + 0.5f * peak;
    int lo = kmax, hi = kmax;
    while (lo > first && profile[static_cast<std::size_t>(lo - 1)] > half) --lo;
    while (hi < last && profile[static_cast<std::size_t>(hi + 1)] > half) ++hi;
    if (hi - lo + 1 > options.max_stripe_width_px || lo == first || hi == last) continue;
    // A second stripe (reflection, the wall behind) as strong as the first: ambiguous.
    bool ambiguous = false;
    const float second = background + static_cast<float>(options.ambiguity_ratio) * peak;
    for (int k = first; k <= last && !ambiguous; ++k) {
      if ((k < lo - options.max_stripe_width_px || k > hi + options.max_stripe_width_px) &&
          profile[static_cast<std::size_t>(k)] > second) {
        ambiguous = true;
      }
    }
    if (ambiguous) continue;
    // Centre of gravity of the samples above half maximum, background removed.
    double sw = 0, swk = 0;
    for (int k = std::max(first, lo - 1); k <= std::min(last, hi + 1); ++k) {
      const double w = std::max(0.0f, profile[static_cast<std::size_t>(k)] - half);
      sw += w;
      swk += w * k;
    }
    if (!(sw > 0)) continue;
    double position = swk / sw;
    // Gaussian three-point estimator (log-parabola through the maximum and its neighbours): far
    // less pixel-locking than the centre of gravity on a narrow stripe; the centre of gravity is
    // kept for flat (saturated) tops.
    const double a = profile[static_cast<std::size_t>(kmax - 1)] - background;
    const double b = profile[static_cast<std::size_t>(kmax)] - background;
    const double c = profile[static_cast<std::size_t>(kmax + 1)] - background;
    if (a > 0 && c > 0 && b > a && b > c) {
      const double la = std::log(a), lb = std::log(b), lc = std::log(c);
      const double denom = la - 2 * lb + lc;
      if (denom < 0) position = kmax + 0.5 * (la - lc) / denom;
    }
    peaks.push_back(along_rows ? Eigen::Vector2d(position, line) : Eigen::Vector2d(line, position));
  }
  return peaks;
}

}  // namespace lasercell::calib::internal
