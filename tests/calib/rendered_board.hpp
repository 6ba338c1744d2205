#pragma once
// The calib BoardSpec of the simulator's chessboard target (datasets/camera_images.hpp): its
// inner-corner grid and square size, for tests that detect boards in rendered images.
#include "calib/board.hpp"
#include "datasets/camera_images.hpp"

namespace lasercell::calib {

inline BoardSpec BoardOf(const datasets::ChessboardTarget& target) {
  return BoardSpec::Chessboard(target.squares_x - 1, target.squares_y - 1, target.square_mm);
}

}  // namespace lasercell::calib
