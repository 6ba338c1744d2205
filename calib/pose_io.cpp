// Robot pose files (pose_io.hpp).
#include "calib/pose_io.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
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

// An Euler angle beyond this is not in degrees: swapped columns or another unit. (Radians stay
// within +-2 pi and pass; nothing in the file tells them apart from small angles in degrees.)
constexpr double kMaxAngleDeg = 360.0;

// Splits a line at whitespace and commas.
std::vector<std::string> Tokens(std::string line) {
  std::replace(line.begin(), line.end(), ',', ' ');
  std::istringstream ls(line);
  std::vector<std::string> out;
  for (std::string t; ls >> t;) out.push_back(t);
  return out;
}

// The whole token as a number ("nan" and "inf" included: the callers check finiteness); false
// for text or a number out of double range.
bool ParseNumber(const std::string& token, double* value) {
  const char* first = token.data();
  const char* last = token.data() + token.size();
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') ++first;  // from_chars rejects '+'
  const auto r = std::from_chars(first, last, *value);
  return r.ec == std::errc() && r.ptr == last && first != last;
}

// A line of the text layout that holds a pose: not blank, not a '#' comment.
bool IsPoseLine(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first != std::string::npos && line[first] != '#';
}

// The first character that is not blank or a UTF-8 byte order mark, '\0' for none.
char FirstNonBlank(const std::string& text) {
  std::size_t i = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  i = text.find_first_not_of(" \t\r\n", i);
  return i == std::string::npos ? '\0' : text[i];
}

// Names of the three angles of a convention, in the order they appear on a line.
std::array<const char*, 3> AngleLabels(EulerConvention convention) {
  if (convention == EulerConvention::kFanucXyzwpr) return {"w", "p", "r"};
  return {"A", "B", "C"};
}

// x y z (mm) + three angles (degrees) as base_from_flange; `where` locates the pose in errors.
Eigen::Isometry3d EulerPose(const std::array<double, 6>& v, EulerConvention convention,
                            const std::string& name, const std::string& where) {
  const std::array<const char*, 3> angle = AngleLabels(convention);
  const std::array<const char*, 6> label = {"x", "y", "z", angle[0], angle[1], angle[2]};
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw FileError(name, where + ": " + label[i] + " is not a finite number; expected 6 " +
                                "finite numbers for " + EulerConventionName(convention));
    }
  }
  for (std::size_t i = 3; i < v.size(); ++i) {
    if (std::abs(v[i]) > kMaxAngleDeg) {
      throw FileError(name, where + ": angle " + label[i] + " = " + Fmt("%g", v[i]) +
                                " is beyond +-360: angles must be degrees (" +
                                EulerConventionName(convention) + ")");
    }
  }
  // Both conventions are R = Rz * Ry * Rx (rotations about the fixed base axes, x first);
  // Fanuc lists the angles x-first (w p r), KUKA z-first (A B C).
  const bool fanuc = convention == EulerConvention::kFanucXyzwpr;
  const Eigen::Vector3d xyz_deg(fanuc ? v[3] : v[5], v[4], fanuc ? v[5] : v[3]);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = RotationFromFixedXyzDeg(xyz_deg);
  pose.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return pose;
}

// The text layout: one pose per line.
RobotPoses ParseEulerText(const std::string& text, const std::string& name,
                          EulerConvention convention) {
  RobotPoses out;
  std::istringstream in(text);
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (!IsPoseLine(line)) continue;
    const std::string where = "line " + std::to_string(line_no);
    const std::vector<std::string> tokens = Tokens(line);
    std::array<double, 6> v{};
    for (std::size_t i = 0; i < tokens.size(); ++i) {
      double x = 0;
      if (!ParseNumber(tokens[i], &x)) {
        throw FileError(name, where + ": '" + tokens[i] + "' is not a number; expected 6 " +
                                  "numbers for " + EulerConventionName(convention));
      }
      if (i < v.size()) v[i] = x;
    }
    if (tokens.size() != v.size()) {
      throw FileError(
          name, where + ": expected 6 numbers for " + EulerConventionName(convention) + ", got " +
                    std::to_string(tokens.size()) +
                    (tokens.size() == 16 ? " (a 4x4 matrix: use the kuka format)" : ""));
    }
    out.base_from_flange.push_back(EulerPose(v, convention, name, where));
  }
  return out;
}

// The JSON layout of RobCalibrator's .rob files: {"RobPoses": [[x, y, z, a1, a2, a3], ...]}.
RobotPoses ParseEulerJson(const std::string& text, const std::string& name,
                          EulerConvention convention) {
  const std::string expected = R"(expected {"RobPoses": [[x, y, z, angle, angle, angle], ...]})";
  nlohmann::json top;
  try {
    top = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw FileError(name, std::string("not valid JSON (") + e.what() + "); " + expected);
  }
  if (!top.is_object()) throw FileError(name, "not a JSON object; " + expected);
  for (auto it = top.begin(); it != top.end(); ++it) {
    if (it.key() != "RobPoses") {
      throw FileError(name, "unknown key \"" + it.key() + "\"; " + expected);
    }
  }
  if (!top.contains("RobPoses") || !top["RobPoses"].is_array()) {
    throw FileError(name, "\"RobPoses\" must be a list of poses; " + expected);
  }
  const nlohmann::json& rows = top["RobPoses"];
  RobotPoses out;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string where =
        "pose " + std::to_string(i + 1) + " (RobPoses[" + std::to_string(i) + "])";
    const nlohmann::json& row = rows[i];
    bool numbers = row.is_array() && row.size() == 6;
    for (std::size_t k = 0; numbers && k < row.size(); ++k) numbers = row[k].is_number();
    if (!numbers) {
      std::string got = row.dump();
      if (got.size() > 80) got = got.substr(0, 77) + "...";
      throw FileError(name, where + ": expected 6 numbers for " + EulerConventionName(convention) +
                                ", got " + got);
    }
    std::array<double, 6> v{};
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = row[k].get<double>();
    out.base_from_flange.push_back(EulerPose(v, convention, name, where));
  }
  return out;
}

// How the text gives x y z + Euler-angle poses ("" when it does not): a RobPoses JSON, or a
// first pose line of exactly 6 numbers.
std::string EulerLayout(const std::string& text) {
  if (FirstNonBlank(text) == '{') {
    return text.find("\"RobPoses\"") != std::string::npos ? "a RobCalibrator RobPoses JSON" : "";
  }
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!IsPoseLine(line)) continue;
    const std::vector<std::string> tokens = Tokens(line);
    double x = 0;
    const bool six = tokens.size() == 6 &&
                     std::all_of(tokens.begin(), tokens.end(),
                                 [&x](const std::string& t) { return ParseNumber(t, &x); });
    return six ? "lines of 6 numbers" : "";
  }
  return "";
}

}  // namespace

std::string EulerConventionName(EulerConvention convention) {
  switch (convention) {
    case EulerConvention::kFanucXyzwpr:
      return "xyzwpr (Fanuc: x y z mm, w p r degrees, R = Rz(r) Ry(p) Rx(w))";
    case EulerConvention::kKukaXyzabc:
      return "xyzabc (KUKA: x y z mm, A B C degrees, R = Rz(A) Ry(B) Rx(C))";
  }
  return "unknown Euler convention";
}

RobotPoses ParseEulerPoses(const std::string& text, const std::string& name,
                           EulerConvention convention) {
  RobotPoses out = FirstNonBlank(text) == '{' ? ParseEulerJson(text, name, convention)
                                              : ParseEulerText(text, name, convention);
  if (out.base_from_flange.empty()) {
    throw FileError(name, "no poses; expected one pose per line (or a RobPoses JSON) for " +
                              EulerConventionName(convention));
  }
  CheckPoseUnits(out.base_from_flange, name);
  return out;
}

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
    if (!poses.images.empty()) o << "image: " << yaml::Quoted(poses.images[i]) << ", ";
    o << pose.substr(1) << "\n";
  }
  return o.str();
}

namespace {
// True when nothing but white space is left on the line (trailing text is an error, not
// ignored: "board 3 2 25 x" is not a board line).
bool AtLineEnd(std::istringstream& ls) {
  ls >> std::ws;
  return ls.eof();
}
}  // namespace

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
      if (!(ls >> cols >> rows >> square_mm) || !AtLineEnd(ls) || cols < 2 || rows < 2 ||
          !(square_mm > 0)) {
        throw FileError(name, where + ": expected 'board COLS ROWS SQUARE_MM'");
      }
      d.board = BoardSpec::Chessboard(cols, rows, square_mm);
      board_seen = true;
      continue;
    }
    if (key == "image_size") {
      if (!(ls >> d.width_px >> d.height_px) || !AtLineEnd(ls) || d.width_px < 1 ||
          d.height_px < 1) {
        throw FileError(name, where + ": expected 'image_size WIDTH HEIGHT'");
      }
      continue;
    }
    int index = 0;
    double u = 0, v = 0;
    if (!(ls >> index >> u >> v) || !AtLineEnd(ls) || !std::isfinite(u) || !std::isfinite(v)) {
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
  if (d.width_px == 0) throw FileError(name, "no 'image_size WIDTH HEIGHT' line");
  for (std::size_t i = 0; i < d.images.size(); ++i) {
    for (std::size_t k = 0; k < d.corners_px[i].size(); ++k) {
      // Pixel centres run from 0 to size - 1; a corner is at most half a pixel beyond them.
      const Eigen::Vector2d& c = d.corners_px[i][k];
      if (c.x() < -0.5 || c.y() < -0.5 || c.x() > d.width_px - 0.5 || c.y() > d.height_px - 0.5) {
        throw FileError(name, d.images[i] + ": corner " + std::to_string(k) + " (" +
                                  FormatDouble(c.x()) + ", " + FormatDouble(c.y()) +
                                  ") px lies outside the " + std::to_string(d.width_px) + " x " +
                                  std::to_string(d.height_px) + " image");
      }
    }
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
  return ParseRobotPoses(io::ReadFileBytes(path), path, format);
}

RobotPoses ParseRobotPoses(const std::string& text, const std::string& path,
                           const std::string& format) {
  std::string f = format;
  if (f == "auto") {
    const std::string euler = EulerLayout(text);
    if (text.find("format:") != std::string::npos) {
      f = "yaml";
    } else if (!euler.empty()) {
      // The same six numbers give different rotations in the two conventions: never guess.
      throw FileError(path, "holds x y z + Euler-angle poses (" + euler +
                                ") but does not state its Euler convention; pass the format "
                                "explicitly: xyzwpr for Fanuc (x y z w p r) or xyzabc for "
                                "KUKA (x y z A B C)");
    } else {
      f = "kuka";
    }
  }
  if (f == "kuka") return ParseKukaPoses(text, path);
  if (f == "yaml") return ParseYamlPoses(text, path);
  if (f == "xyzwpr") return ParseEulerPoses(text, path, EulerConvention::kFanucXyzwpr);
  if (f == "xyzabc") return ParseEulerPoses(text, path, EulerConvention::kKukaXyzabc);
  throw OptionError("--pose-format must be kuka, yaml, xyzwpr, xyzabc or auto, not '" + format +
                    "'");
}

}  // namespace lasercell::calib
