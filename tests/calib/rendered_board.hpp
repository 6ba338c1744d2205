#pragma once
// The calib BoardSpec of the simulator's chessboard target (datasets/camera_images.hpp): its
// inner-corner grid and square size, for tests that detect boards in rendered images.
#include "calib/board.hpp"
#include "datasets/camera_images.hpp"

namespace lasercell::calib {

inline BoardSpec BoardOf(const datasets::ChessboardTarget& target) {
  BoardSpec board;  // chessboard
  board.cols = target.squares_x - 1;
  board.rows = target.squares_y - 1;
  board.square_mm = target.square_mm;
  return board;
}

}  // namespace lasercell::calib
