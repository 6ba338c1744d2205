#pragma once
// Calibrating a cell from a capture folder laid out as `lasercell simulate cell` writes it, the
// way a user does with the command line (README: calibrate camera -> calibrate laser -> scan
// triangulate -> calibrate spheres), reading only what a real cell records (images/, profiles/,
// records/) and never truth/:
//   1. camera intrinsics (OPENCV8) from images/chessboard_*.png (board from `board`); when the
//      OPENCV8 fit folds over inside the imager (its rational terms cancel where the boards were
//      and diverge elsewhere, calib::LensInversionProblem), OPENCV5 is fitted instead and the
//      summary says so, as an engineer would do by hand,
//   2. the laser plane from profiles/plane_<i>.lcp at the heights of records/planes.yaml,
//   3. handling_base <- sensor (at the linear sweep's t0) from profiles/spheres.lcp, triangulated
//      with 1-2 and placed by records/linear_sweep.yaml, and records/touches.yaml.
// Writes out_dir/camera.cameramodel and out_dir/cell.yaml (the laser plane and the edge with
// their covariances and provenance). Units mm.

#include <string>

#include "calib/board.hpp"
#include "core/progress.hpp"

namespace lasercell::datasets {

/// What CalibrateCaptureFolder produced.
struct CaptureCalibration {
  std::string camera_file;  ///< out_dir/camera.cameramodel.
  std::string cell_file;    ///< out_dir/cell.yaml.
  std::string camera_summary;
  std::string laser_summary;
  std::string spheres_summary;
  double seconds = 0.0;  ///< Wall time.
};

/// Runs steps 1-3 (see the file comment). Throws InputError / FileError naming the folder or
/// file when a capture is missing or a calibration is refused.
CaptureCalibration CalibrateCaptureFolder(const std::string& capture_dir,
                                          const std::string& out_dir, const calib::BoardSpec& board,
                                          const ProgressCallback& progress = {}, int threads = 0);

}  // namespace lasercell::datasets
