// Calibrated profiles written by other software (foreign_profiles.hpp).
#include "triangulation/foreign_profiles.hpp"

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>

#include "calib/pose_io.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::triangulation {
namespace {

const char* const kExpected =
    "expected an OpenCV FileStorage YAML file ('%YAML:1.0') with a `scan_line` key holding a "
    "flat sequence of x, y, z triples in mm";

// The numbers of `scan_line`, in file order; FileError for a missing key or non-numbers,
// cv::Exception from OpenCV for text it cannot parse.
std::vector<double> ScanLineValues(const std::string& text, const std::string& path) {
  // From memory: the file was read (and its absence reported) by ReadFileBytes, and OpenCV
  // then decides the format from the content, not from the file name.
  const cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  if (!fs.isOpened()) throw FileError(path, std::string("cannot be read; ") + kExpected);
  const cv::FileNode node = fs["scan_line"];
  if (node.isNone()) throw FileError(path, std::string("no `scan_line` key; ") + kExpected);
  if (!node.isSeq()) {
    throw FileError(path, std::string("`scan_line` is not a sequence of numbers; ") + kExpected);
  }
  std::vector<double> values;
  values.reserve(node.size());
  for (auto it = node.begin(); it != node.end(); ++it) {
    const cv::FileNode value = *it;
    if (!value.isReal() && !value.isInt()) {
      throw FileError(path, "`scan_line` element " + std::to_string(values.size() + 1) +
                                " is not a number; " + kExpected);
    }
    values.push_back(static_cast<double>(value));
  }
  return values;
}

// OpenCV's message without its trailing newline.
std::string OpenCvMessage(const cv::Exception& e) {
  std::string m = e.what();
  while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
  return m;
}

}  // namespace

ScanLineProfile ReadScanLineProfile(const std::string& path) {
  const std::string text = io::ReadFileBytes(path);
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
    throw FileError(path, std::string("empty file; ") + kExpected);
  }
  std::vector<double> values;
  try {
    values = ScanLineValues(text, path);
  } catch (const cv::Exception& e) {
    throw FileError(path,
                    "not readable as OpenCV FileStorage (" + OpenCvMessage(e) + "); " + kExpected);
  }
  if (values.size() % 3 != 0) {
    throw FileError(path, "`scan_line` holds " + std::to_string(values.size()) +
                              " numbers, not a multiple of 3: expected x, y, z triples");
  }
  ScanLineProfile out;
  out.columns = values.size() / 3;
  for (std::size_t i = 0; i < out.columns; ++i) {
    const Eigen::Vector3d p(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
    const std::string where = "`scan_line` point " + std::to_string(i + 1);
    if (p.array().isInf().any()) {
      throw FileError(path, where + ": infinite value; a column without a peak must be .Nan");
    }
    if (p.array().isNaN().any()) {
      ++out.missing;
      continue;
    }
    if (std::abs(p.y()) > kScanLinePlaneTolerance) {
      char y[64];
      std::snprintf(y, sizeof y, "%.6g", p.y());
      throw FileError(path, where + ": not a profile in the laser plane: y = " + y +
                                " mm (expected (x, 0, z) points in the sensor frame)");
    }
    out.points_in_sensor.push_back(p);
  }
  if (out.points_in_sensor.empty()) {
    throw FileError(path, out.columns == 0 ? std::string("`scan_line` is empty: no point")
                                           : "no finite point: all " + std::to_string(out.columns) +
                                                 " columns are NaN (the sensor saw no peak)");
  }
  return out;
}

std::vector<calib::SphereSectionProfile> LoadSphereSections(
    const std::vector<std::string>& profile_paths, const std::string& poses_path,
    const std::string& pose_format) {
  const calib::RobotPoses poses = calib::LoadRobotPoses(poses_path, pose_format);
  if (poses.base_from_flange.size() != profile_paths.size()) {
    throw OptionError(std::to_string(profile_paths.size()) + " profiles but " +
                      std::to_string(poses.base_from_flange.size()) + " poses in " + poses_path +
                      "; give one profile per pose, in pose order");
  }
  std::vector<calib::SphereSectionProfile> sections;
  for (std::size_t i = 0; i < profile_paths.size(); ++i) {
    sections.push_back({profile_paths[i], poses.base_from_flange[i],
                        ReadScanLineProfile(profile_paths[i]).points_in_sensor});
  }
  return sections;
}

}  // namespace lasercell::triangulation
