#include "calib/kuka2_set.hpp"

#include <cstdio>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <vector>

#include "calib/board.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::calib {

bool HasKuka2Set(const std::string& dir) {
  return std::filesystem::exists(dir + "/im_01.png") &&
         std::filesystem::exists(dir + "/RobotPosesVec.txt");
}

Kuka2Set LoadKuka2Set(const std::string& dir, const DetectionOptions& detection) {
  Kuka2Set k;
  k.dir = dir;
  ChessboardDetections& det = k.detections;
  det.board = BoardSpec::Chessboard(24, 17, 15.0);
  const BoardSpec& spec = det.board;
  const std::vector<Eigen::Vector3d> board = spec.Corners();
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<std::vector<cv::Point2f>> img;
  for (int i = 1; i <= kKuka2Images; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "im_%02d.png", i);
    const std::string path = dir + "/" + name;
    const TargetDetection found =
        DetectTargetInEncodedImage(io::ReadFileBytes(path), spec, detection);
    if (!found.found()) {
      k.error = "kuka2: " + path + ": " + found.message;
      k.error_status = found.status;
      return k;
    }
    det.width_px = found.width;
    det.height_px = found.height;
    det.images.push_back(name);
    det.corners_px.push_back(found.corners_px);
    std::vector<cv::Point3f> o;
    std::vector<cv::Point2f> p;
    for (std::size_t j = 0; j < found.corners_px.size(); ++j) {
      const Eigen::Vector2d& c = found.corners_px[j];
      o.emplace_back(static_cast<float>(board[j].x()), static_cast<float>(board[j].y()), 0.f);
      p.emplace_back(static_cast<float>(c.x()), static_cast<float>(c.y()));
    }
    obj.push_back(o);
    img.push_back(p);
  }
  cv::Mat km, d;
  std::vector<cv::Mat> rv, tv;
  k.calibration_rms_px =
      cv::calibrateCamera(obj, img, cv::Size(det.width_px, det.height_px), km, d, rv, tv);
  std::vector<double> intr = {km.at<double>(0, 0), km.at<double>(1, 1), km.at<double>(0, 2),
                              km.at<double>(1, 2)};
  for (int i = 0; i < 5; ++i) intr.push_back(d.at<double>(i));
  k.camera.emplace("LENSMODEL_OPENCV5", intr, det.width_px, det.height_px);
  return k;
}

}  // namespace lasercell::calib
