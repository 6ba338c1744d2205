// Robot pose files (pose_io.hpp).
#include "calib/pose_io.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/se3.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell::calib {
namespace {

constexpr double kOrthonormalTolerance = 1e-6;

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

std::string Fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// A YAML record's root as a Fields walker (FileError), its format and version checked.
yaml::Fields RecordFields(const std::string& text, const std::string& name, const char* format) {
  yaml::Fields top = yaml::Fields::Parse(text, name, yaml::ErrorKind::kFile);
  top.RequireFormat(format, 1);
  return top;
}

}  // namespace

void CheckPoseUnits(const std::vector<Eigen::Isometry3d>& base_from_flange,
                    const std::string& name) {
  if (base_from_flange.empty()) throw FileError(name, "no poses");
  int small = 0, large = 0;
  for (const auto& p : base_from_flange) {
    const double n = p.translation().norm();
    if (n < 5.0) ++small;
    if (n > 50.0) ++large;
  }
  const int count = static_cast<int>(base_from_flange.size());
  if (small == count) {
    throw FileError(name,
                    "every translation is below 5 mm: the poses look like metres; give "
                    "mm (or use the kuka format, which is in metres)");
  }
  if (small > 0 && large > 0) {
    throw FileError(name, std::to_string(small) + " of " + std::to_string(count) +
                              " translations are below 5 mm while " + std::to_string(large) +
                              " are above 50 mm: mixed units (metres and mm?)");
  }
}

RobotPoses ParseKukaPoses(const std::string& text, const std::string& name) {
  RobotPoses out;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::replace(line.begin(), line.end(), ',', ' ');
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ls(line);
    std::vector<double> v;
    double x;
    while (ls >> x) v.push_back(x);
    const std::string where = "line " + std::to_string(line_no);
    if (!ls.eof() || v.size() != 16) {
      throw FileError(name, where +
                                ": expected 16 numbers (row-major 4x4 base->TCP, metres), got " +
                                std::to_string(v.size()) + (ls.eof() ? "" : " and text"));
    }
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    }
    if (!m.allFinite()) throw FileError(name, where + ": non-finite number");
    if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
      throw FileError(name, where + ": last row must be 0 0 0 1");
    }
    const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
    const double err = (r.transpose() * r - Eigen::Matrix3d::Identity()).norm();
    if (err > kOrthonormalTolerance || r.determinant() <= 0) {
      throw FileError(name, where + ": rotation is not orthonormal (|R^T R - I| = " +
                                Fmt("%.3g", err) + ", det " + Fmt("%.6f", r.determinant()) + ")");
    }
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.linear() = NearestRotation(r);
    p.translation() = 1000.0 * m.topRightCorner<3, 1>();  // metres -> mm
    out.base_from_flange.push_back(p);
  }
  if (out.base_from_flange.empty()) throw FileError(name, "no poses");
  // The kuka form is metres: a file already in mm would give translations > 50 m.
  for (std::size_t i = 0; i < out.base_from_flange.size(); ++i) {
    if (out.base_from_flange[i].translation().norm() > 50000.0) {
      throw FileError(name, "pose " + std::to_string(i + 1) +
                                ": translation above 50 m: the kuka form is in metres; this "
                                "file looks like mm (use --pose-format yaml)");
    }
  }
  CheckPoseUnits(out.base_from_flange, name);
  return out;
}

RobotPoses ParseYamlPoses(const std::string& text, const std::string& name) {
  yaml::Fields top = RecordFields(text, name, "lasercell.robot_poses");
  top.Known("poses");
  top.Done();
  if (!top.Has("poses")) top.Fail("poses", "is required: a non-empty list of poses");
  std::vector<yaml::Fields> poses = top.List("poses");
  if (poses.empty()) top.Fail("poses", "must be a non-empty list");
  RobotPoses out;
  for (yaml::Fields& p : poses) {
    p.Known({"image", "translation_mm", "rotation_wxyz"});
    p.Done();
    out.base_from_flange.push_back(p.ReadPoseFields().ToIsometry());
    std::string image;
    if (p.Read("image", &image)) out.images.push_back(image);
  }
  if (!out.images.empty() && out.images.size() != out.base_from_flange.size()) {
    throw FileError(name, "`image` must be given for every pose or for none");
  }
  CheckPoseUnits(out.base_from_flange, name);
  return out;
}

HandEyeImagesRecord ParseHandEyeImagesRecord(const std::string& text, const std::string& name) {
  yaml::Fields top = RecordFields(text, name, "lasercell.hand_eye_images");
  top.Known({"robot", "board", "images"});
  top.Done();
  HandEyeImagesRecord out;
  top.ReadRequired("robot", &out.robot);
  if (!top.Has("board")) top.Fail("board", "is required: {inner_corners: [cols, rows], square_mm}");
  yaml::Fields board = top.Sub("board");
  board.Known({"squares", "inner_corners", "square_mm"});
  board.Done();
  std::vector<double> inner;
  board.ReadRequired("inner_corners", &inner);
  if (inner.size() != 2 || inner[0] != std::floor(inner[0]) || inner[1] != std::floor(inner[1]) ||
      inner[0] < 2 || inner[1] < 2) {
    board.Fail("inner_corners", "must be [cols, rows], two integers >= 2");
  }
  double square_mm = 0;
  board.ReadRequired("square_mm", &square_mm);
  if (!(square_mm > 0)) board.Fail("square_mm", "must be positive");
  out.board =
      BoardSpec::Chessboard(static_cast<int>(inner[0]), static_cast<int>(inner[1]), square_mm);
  for (yaml::Fields& im : top.List("images")) {
    im.Known({"file", "joints_rad"});
    im.Done();
    std::string file;
    std::vector<double> joints;
    im.ReadRequired("file", &file);
    im.ReadRequired("joints_rad", &joints);
    out.images.push_back(file);
    out.joints_rad.push_back(joints);
  }
  if (out.images.empty()) top.Fail("images", "must list at least one image");
  return out;
}

std::string RobotPosesYaml(const RobotPoses& poses) {
  std::ostringstream o;
  o << "format: lasercell.robot_poses\nversion: 1\n# base_from_flange of each image, mm\nposes:\n";
  for (std::size_t i = 0; i < poses.base_from_flange.size(); ++i) {
    const std::string pose = PoseToFileNotation(poses.base_from_flange[i]);
    o << "  - {";
    if (!poses.images.empty()) o << "image: " << poses.images[i] << ", ";
    o << pose.substr(1) << "\n";
  }
  return o.str();
}

ChessboardDetections ParseChessboardDetections(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  ChessboardDetections d;
  bool header = false;
  bool board_seen = false;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string where = "line " + std::to_string(line_no);
    if (line_no == 1) {
      if (line.rfind("# lasercell-chessboard-corners v1", 0) != 0) {
        throw FileError(name, "first line must be '# lasercell-chessboard-corners v1'");
      }
      header = true;
      continue;
    }
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "board") {
      int cols = 0, rows = 0;
      double square_mm = 0;
      if (!(ls >> cols >> rows >> square_mm) || cols < 2 || rows < 2 || !(square_mm > 0)) {
        throw FileError(name, where + ": expected 'board COLS ROWS SQUARE_MM'");
      }
      d.board = BoardSpec::Chessboard(cols, rows, square_mm);
      board_seen = true;
      continue;
    }
    if (key == "image_size") {
      if (!(ls >> d.width_px >> d.height_px) || d.width_px < 1 || d.height_px < 1) {
        throw FileError(name, where + ": expected 'image_size WIDTH HEIGHT'");
      }
      continue;
    }
    int index = 0;
    double u = 0, v = 0;
    if (!(ls >> index >> u >> v) || !std::isfinite(u) || !std::isfinite(v)) {
      throw FileError(name, where + ": expected 'IMAGE CORNER_INDEX U_PX V_PX'");
    }
    if (!board_seen) throw FileError(name, where + ": corner before the 'board' line");
    if (d.images.empty() || d.images.back() != key) {
      d.images.push_back(key);
      d.corners_px.emplace_back();
    }
    if (index != static_cast<int>(d.corners_px.back().size())) {
      throw FileError(
          name, where + ": corner index " + std::to_string(index) + " of " + key + " out of order");
    }
    d.corners_px.back().emplace_back(u, v);
  }
  if (!header) throw FileError(name, "empty file");
  for (std::size_t i = 0; i < d.images.size(); ++i) {
    if (d.corners_px[i].size() != static_cast<std::size_t>(d.board.NumCorners())) {
      throw FileError(name, d.images[i] + ": " + std::to_string(d.corners_px[i].size()) +
                                " corners, expected " + std::to_string(d.board.NumCorners()));
    }
  }
  if (d.images.empty()) throw FileError(name, "no corners");
  return d;
}

std::string ChessboardDetectionsText(const ChessboardDetections& d, const std::string& comment) {
  std::ostringstream o;
  o << "# lasercell-chessboard-corners v1\n";
  std::istringstream c(comment);
  for (std::string l; std::getline(c, l);) o << "# " << l << "\n";
  o << "board " << d.board.cols << " " << d.board.rows << " " << FormatDouble(d.board.square_mm)
    << "\n"
    << "image_size " << d.width_px << " " << d.height_px << "\n";
  for (std::size_t i = 0; i < d.images.size(); ++i) {
    for (std::size_t k = 0; k < d.corners_px[i].size(); ++k) {
      char b[64];  // 1e-4 px: far below any detector's precision
      std::snprintf(b, sizeof b, " %.4f %.4f\n", d.corners_px[i][k].x(), d.corners_px[i][k].y());
      o << d.images[i] << " " << k << b;
    }
  }
  return o.str();
}

RobotPoses LoadRobotPoses(const std::string& path, const std::string& format) {
  const std::string text = io::ReadFileBytes(path);
  std::string f = format;
  if (f == "auto") f = text.find("format:") != std::string::npos ? "yaml" : "kuka";
  if (f == "kuka") return ParseKukaPoses(text, path);
  if (f == "yaml") return ParseYamlPoses(text, path);
  throw OptionError("--pose-format must be kuka, yaml or auto, not '" + format + "'");
}

}  // namespace lasercell::calib
