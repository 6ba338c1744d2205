#include "triangulation/laser_plane_captures.hpp"

#include <cmath>
#include <filesystem>
#include <map>
#include <regex>
#include <system_error>

#include "core/error.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::triangulation {

std::vector<std::string> FindPlaneProfileFiles(const std::string& dir) {
  std::map<long, std::string> files;
  const std::regex pattern("plane_([0-9]+)\\.lcp");
  for (const std::string& d : {dir, dir + "/profiles"}) {
    std::error_code ec;
    if (!std::filesystem::is_directory(d, ec)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(d, ec)) {
      std::smatch match;
      const std::string name = entry.path().filename().string();
      if (std::regex_match(name, match, pattern))
        files[std::stol(match[1])] = entry.path().string();
    }
    if (!files.empty()) break;
  }
  if (files.empty()) {
    throw FileError(dir,
                    "holds no plane_<i>.lcp profile files (nor does its profiles/ folder); "
                    "pass the folder of the white-plane sweeps");
  }
  std::vector<std::string> out;
  for (auto& [i, path] : files) out.push_back(path);
  return out;
}

calib::HeightCapture HeightCaptureFromProfiles(const ProfileSet& set, const std::string& name,
                                               double height_mm) {
  calib::HeightCapture c;
  c.name = name;
  c.height_mm = height_mm;
  for (const auto& p : set.profiles) {
    for (std::size_t j = 0; j < p.row_px.size(); ++j) {
      if (std::isfinite(p.row_px[j])) {
        c.peaks_px.emplace_back(static_cast<double>(set.header.first_column + j), p.row_px[j]);
      }
    }
  }
  return c;
}

std::vector<calib::HeightCapture> LoadHeightCaptures(const std::vector<std::string>& files,
                                                     const std::vector<double>& heights_mm,
                                                     const calib::CameraModel& camera,
                                                     InputDigest* digest) {
  if (files.size() != heights_mm.size()) {
    throw OptionError(std::to_string(files.size()) + " plane_<i>.lcp files but " +
                      std::to_string(heights_mm.size()) + " heights; give one height per file");
  }
  std::vector<calib::HeightCapture> captures;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::string bytes = io::ReadFileBytes(files[i]);
    if (digest != nullptr) digest->Add(bytes);
    const ProfileSet set = DecodeProfiles(bytes, files[i]);
    if (static_cast<int>(set.header.image_width) != camera.width_px() ||
        static_cast<int>(set.header.image_height) != camera.height_px()) {
      throw FileError(files[i], "was recorded with a " + std::to_string(set.header.image_width) +
                                    "x" + std::to_string(set.header.image_height) +
                                    " sensor but the camera model is " +
                                    std::to_string(camera.width_px()) + "x" +
                                    std::to_string(camera.height_px()));
    }
    captures.push_back(HeightCaptureFromProfiles(set, files[i], heights_mm[i]));
  }
  return captures;
}

calib::LaserPlaneResult CalibrateLaserPlaneFromPlaneFiles(const calib::CameraModel& camera,
                                                          const std::string& dir,
                                                          const std::vector<double>& heights_mm,
                                                          const calib::HeightPlaneOptions& options,
                                                          InputDigest* digest) {
  const std::vector<std::string> files = FindPlaneProfileFiles(dir);
  const auto captures = LoadHeightCaptures(files, heights_mm, camera, digest);
  return calib::CalibrateLaserPlaneFromHeights(camera, captures, options);
}

calib::LaserPlaneResult CalibrateLaserPlaneFromStripeFiles(const calib::CameraModel& camera,
                                                           const std::vector<std::string>& paths,
                                                           const calib::BoardSpec& board,
                                                           const calib::StripeOptions& options,
                                                           InputDigest* digest) {
  std::vector<calib::StripeImage> images;
  for (const std::string& path : paths) {
    const std::string bytes = io::ReadFileBytes(path);
    if (digest != nullptr) digest->Add(bytes);
    images.push_back(calib::DecodeStripeImage(bytes, path));
  }
  return calib::CalibrateLaserPlaneFromStripes(camera, images, board, options);
}

}  // namespace lasercell::triangulation
