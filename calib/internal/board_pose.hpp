#pragma once
// Board pose from one view (private to calib/): planar PnP on normalised image coordinates, so
// any lens model (calib/camera_model.hpp) can feed it through its unprojection. Used by the
// hand-eye calibration and the stripe-on-chessboard laser calibration. Units: mm.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace lasercell::calib::internal {

/// camera_from_board from board points (z = 0) and their normalised image coordinates (x/z, y/z
/// of the camera rays): OpenCV solvePnP IPPE (closed form for planar targets) refined by the
/// iterative Levenberg-Marquardt, with an identity camera matrix and no distortion.
Eigen::Isometry3d SolvePnPNormalised(const std::vector<Eigen::Vector3d>& p_in_board,
                                     const std::vector<Eigen::Vector2d>& normalised);

}  // namespace lasercell::calib::internal
