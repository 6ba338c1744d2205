#pragma once
// Private helpers of the stripe-on-chessboard laser calibration (calib/laser_plane_stripe.cpp):
// board pose through the camera model, the laser channel of a colour image, and one subpixel
// laser-stripe peak per scan line inside the board region. The board itself is found by the
// shared detector, calib/target_detection.hpp.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/laser_plane.hpp"
#include "calib/target_detection.hpp"
#include "core/image8.hpp"

namespace lasercell::calib::internal {

/// camera_from_board from corners: rays from the camera model (mrcal unprojection), normalized
/// to z = 1, then SolvePnPNormalised (calib/internal/board_pose.hpp); board corner (i, j) at
/// (i s, j s, 0). `rms_px` gets the reprojection RMS through the camera model.
Eigen::Isometry3d BoardPose(const CameraModel& camera, const std::vector<Eigen::Vector2d>& corners,
                            const BoardSpec& board, double* rms_px);

/// One peak per scan line (image column, or image row when `along_rows`) of the laser channel
/// inside `region` (a convex polygon in pixels): the maximum, rejected below the contrast or
/// when a second maximum is too strong, refined by the centre of gravity of the samples above
/// half the peak. Returns (column, row) pixels.
std::vector<Eigen::Vector2d> StripePeaks(const cv::Mat& laser,
                                         const std::vector<cv::Point2f>& region, bool along_rows,
                                         const StripeOptions& options);

/// The laser channel (CV_32F) of a gray or BGR image for the configured colour.
cv::Mat LaserChannel(const Image8& image, const std::string& color);
/// The image as 8-bit gray.
cv::Mat GrayOf(const Image8& image);
/// The same as a one-channel Image8, the board detector's input.
Image8 Gray8Of(const Image8& image);

}  // namespace lasercell::calib::internal
