#include "calib/board.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/error.hpp"

namespace lasercell::calib {
namespace {

const char* kForms =
    "expected chessboard:COLSxROWS:SQUARE_MM (inner corners, e.g. chessboard:9x6:25) or "
    "charuco:SXxSY:SQUARE_MM:MARKER_MM[:DICT] (squares, e.g. charuco:5x7:40:30:DICT_4X4_50)";

std::vector<std::string> Split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, sep)) parts.push_back(part);
  if (!text.empty() && text.back() == sep) parts.emplace_back();
  return parts;
}

double ParseNumber(const std::string& s, const std::string& text, const char* what) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v)) {
    throw InputError("board '" + text + "': " + what + " '" + s + "' is not a number; " + kForms);
  }
  return v;
}

int ParseCount(const std::string& s, const std::string& text, const char* what) {
  const double v = ParseNumber(s, text, what);
  if (v != std::floor(v)) {
    throw InputError("board '" + text + "': " + what + " '" + s + "' is not an integer; " + kForms);
  }
  return static_cast<int>(v);
}

}  // namespace

void BoardSpec::Check() const {
  const int min_count = type == BoardType::kChessboard ? 2 : 3;
  if (cols < min_count || cols > 1000) {
    throw OptionError("BoardSpec.cols = " + std::to_string(cols) + " must be in [" +
                      std::to_string(min_count) + ", 1000]");
  }
  if (rows < min_count || rows > 1000) {
    throw OptionError("BoardSpec.rows = " + std::to_string(rows) + " must be in [" +
                      std::to_string(min_count) + ", 1000]");
  }
  if (!(square_mm > 0) || !std::isfinite(square_mm)) {
    throw OptionError("BoardSpec.square_mm must be positive (mm)");
  }
  if (type == BoardType::kCharuco) {
    if (!(marker_mm > 0) || !(marker_mm < square_mm)) {
      throw OptionError("BoardSpec.marker_mm must be in (0, square_mm) for a ChArUco board");
    }
    if (dictionary.rfind("DICT_", 0) != 0) {
      throw OptionError("BoardSpec.dictionary '" + dictionary +
                        "' is not an ArUco dictionary name such as DICT_4X4_50");
    }
  }
}

int BoardSpec::CornersX() const { return type == BoardType::kChessboard ? cols : cols - 1; }
int BoardSpec::CornersY() const { return type == BoardType::kChessboard ? rows : rows - 1; }

BoardSpec BoardSpec::Chessboard(int cols, int rows, double square_mm) {
  BoardSpec board;
  board.type = BoardType::kChessboard;
  board.cols = cols;
  board.rows = rows;
  board.square_mm = square_mm;
  return board;
}

Eigen::Vector3d BoardSpec::Corner(int id) const {
  const int nx = CornersX();
  const int c = id % nx;
  const int r = id / nx;
  const double offset = type == BoardType::kChessboard ? 0.0 : 1.0;
  return {(c + offset) * square_mm, (r + offset) * square_mm, 0.0};
}

std::vector<Eigen::Vector3d> BoardSpec::Corners() const {
  std::vector<Eigen::Vector3d> corners;
  corners.reserve(NumCorners());
  for (int id = 0; id < NumCorners(); ++id) corners.push_back(Corner(id));
  return corners;
}

Eigen::Vector2d BoardSpec::Extent() const {
  return {(CornersX() - 1) * square_mm, (CornersY() - 1) * square_mm};
}

std::string BoardSpec::ToString() const {
  std::ostringstream out;
  out.precision(17);
  if (type == BoardType::kChessboard) {
    out << "chessboard:" << cols << "x" << rows << ":" << square_mm;
  } else {
    out << "charuco:" << cols << "x" << rows << ":" << square_mm << ":" << marker_mm << ":"
        << dictionary;
  }
  return out.str();
}

BoardSpec ParseBoardSpec(const std::string& text) {
  const std::vector<std::string> parts = Split(text, ':');
  BoardSpec board;
  if (parts.empty()) throw InputError("board '" + text + "': empty; " + std::string(kForms));
  if (parts[0] == "chessboard") {
    if (parts.size() != 3) throw InputError("board '" + text + "': " + kForms);
    board.type = BoardType::kChessboard;
  } else if (parts[0] == "charuco") {
    if (parts.size() != 4 && parts.size() != 5) throw InputError("board '" + text + "': " + kForms);
    board.type = BoardType::kCharuco;
    board.marker_mm = ParseNumber(parts[3], text, "marker size");
    if (parts.size() == 5) board.dictionary = parts[4];
  } else {
    throw InputError("board '" + text + "': unknown board type '" + parts[0] + "'; " + kForms);
  }
  const std::vector<std::string> size = Split(parts[1], 'x');
  if (size.size() != 2) {
    throw InputError("board '" + text + "': size '" + parts[1] + "' is not COLSxROWS; " + kForms);
  }
  board.cols = ParseCount(size[0], text, "column count");
  board.rows = ParseCount(size[1], text, "row count");
  board.square_mm = ParseNumber(parts[2], text, "square size");
  try {
    board.Check();
  } catch (const OptionError& e) {
    throw InputError("board '" + text + "': " + e.what());
  }
  return board;
}

}  // namespace lasercell::calib
