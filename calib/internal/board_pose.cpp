#include "calib/internal/board_pose.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace lasercell::calib::internal {

Eigen::Isometry3d SolvePnPNormalised(const std::vector<Eigen::Vector3d>& p_in_board,
                                     const std::vector<Eigen::Vector2d>& normalised) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (const auto& p : p_in_board) object.emplace_back(p.x(), p.y(), p.z());
  for (const auto& q : normalised) image.emplace_back(q.x(), q.y());
  cv::Mat rvec, tvec;
  const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
  // IPPE: the planar pose in closed form (Collins & Bartoli 2014); LM polishes it.
  cv::solvePnP(object, image, identity, cv::Mat(), rvec, tvec, false, cv::SOLVEPNP_IPPE);
  cv::solvePnP(object, image, identity, cv::Mat(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
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
