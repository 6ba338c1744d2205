// OpenCV glue of the hand-eye calibration (chessboard_cv.hpp).
#include "calib/internal/chessboard_cv.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/error.hpp"

namespace lasercell::calib::internal {
namespace {

std::optional<std::vector<Eigen::Vector2d>> Detect(const cv::Mat& gray, int cols, int rows) {
  std::vector<cv::Point2f> corners;
  // CALIB_CB_ACCURACY first (found all 28 kuka2 boards); the exhaustive search as a fallback.
  bool found = cv::findChessboardCornersSB(gray, cv::Size(cols, rows), corners,
                                           cv::CALIB_CB_ACCURACY);
  if (!found) {
    found = cv::findChessboardCornersSB(gray, cv::Size(cols, rows), corners,
                                        cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY);
  }
  if (!found || corners.size() != static_cast<std::size_t>(cols * rows)) return std::nullopt;
  cv::cornerSubPix(gray, corners, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
  std::vector<Eigen::Vector2d> out;
  out.reserve(corners.size());
  for (const auto& c : corners) out.emplace_back(c.x, c.y);
  return out;
}

}  // namespace

std::vector<Eigen::Vector3d> ChessboardCorners(int cols, int rows, double square_mm) {
  std::vector<Eigen::Vector3d> out;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) out.emplace_back(c * square_mm, r * square_mm, 0.0);
  }
  return out;
}

std::optional<std::vector<Eigen::Vector2d>> DetectChessboardCorners(
    const std::vector<std::uint8_t>& gray, int width, int height, int cols, int rows) {
  if (gray.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw InputError("chessboard detection: image buffer size does not match width x height");
  }
  const cv::Mat m(height, width, CV_8UC1, const_cast<std::uint8_t*>(gray.data()));
  return Detect(m, cols, rows);
}

std::optional<std::vector<Eigen::Vector2d>> DetectChessboardCornersInFile(
    const std::string& path, int cols, int rows, int* width, int* height) {
  const cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (gray.empty()) throw FileError(path, "cannot read the image");
  if (width) *width = gray.cols;
  if (height) *height = gray.rows;
  return Detect(gray, cols, rows);
}

Eigen::Isometry3d SolvePnPNormalised(const std::vector<Eigen::Vector3d>& p_in_board,
                                     const std::vector<Eigen::Vector2d>& normalised) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const auto& p : p_in_board) object.emplace_back(p.x(), p.y(), p.z());
  for (const auto& q : normalised) image.emplace_back(q.x(), q.y());
  cv::Mat rvec, tvec;
  cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
               cv::SOLVEPNP_ITERATIVE);
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) pose.linear()(i, j) = r.at<double>(i, j);
    pose.translation()[i] = tvec.at<double>(i);
  }
  return pose;
}

}  // namespace lasercell::calib::internal
