// The white-plane method's inputs from files: records/planes.yaml (reader and writer,
// calib/laser_plane_heights_record.hpp) and the plane_<i>.lcp sweeps turned into height
// captures (triangulation/laser_plane_captures.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/laser_plane_heights_record.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "tests/cli_util.hpp"
#include "triangulation/laser_plane_captures.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell {
namespace {

TEST(LaserPlaneHeightsRecord, WritesTheSimulatorsTextAndReadsItBack) {
  calib::PlaneHeightsRecord record;
  record.heights_mm = {150, 250.5, 350};
  record.plate_normal_in_sensor = Eigen::Vector3d(0.1, -0.2, 0.3).normalized();
  const std::string text = calib::PlaneHeightsYaml(record);
  EXPECT_EQ(text.rfind("format: lasercell.plane_heights\nversion: 1\n# profiles/plane_<i>.lcp", 0),
            0u)
      << text;
  EXPECT_NE(text.find("\nheights_mm: [150, 250.5, 350]\nplate_normal_in_sensor: ["),
            std::string::npos)
      << text;
  const calib::PlaneHeightsRecord back = calib::ParsePlaneHeightsYaml(text, "planes.yaml");
  EXPECT_EQ(back.heights_mm, record.heights_mm);
  EXPECT_EQ(back.plate_normal_in_sensor,
            record.plate_normal_in_sensor);  // shortest round-trip text
  // Through a file.
  const test::TestDir dir("planes_record");
  const std::string path = (dir.path() / "planes.yaml").string();
  io::WriteFileAtomically(path, text);
  EXPECT_EQ(calib::ReadPlaneHeightsYaml(path).heights_mm, record.heights_mm);
}

TEST(LaserPlaneHeightsRecord, BadRecordsNameTheField) {
  const std::string ok = "format: lasercell.plane_heights\nversion: 1\n";
  EXPECT_THROW(calib::ParsePlaneHeightsYaml(ok + "plate_normal_in_sensor: [0, 0, -1]\n", "p.yaml"),
               OptionError);  // heights_mm missing
  EXPECT_THROW(
      calib::ParsePlaneHeightsYaml(ok + "heights_mm: [1, 2]\nplate_normal_in_sensor: [0, 0, -1]\n"
                                        "plate_distance: 3\n",
                                   "p.yaml"),
      OptionError);  // unknown field
  EXPECT_THROW(calib::ParsePlaneHeightsYaml(
                   "format: lasercell.other\nheights_mm: [1]\nplate_normal_in_sensor: [0, 0, -1]\n",
                   "p.yaml"),
               Error);
  try {
    calib::ParsePlaneHeightsYaml(ok + "heights_mm: [1, 2]\nplate_normal_in_sensor: [0, 0, 0]\n",
                                 "p.yaml");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("p.yaml: plate_normal_in_sensor must be a finite non-zero"),
        std::string::npos)
        << e.what();
  }
  EXPECT_THROW(calib::ParsePlaneHeightsYaml(
                   ok + "heights_mm: []\nplate_normal_in_sensor: [0, 0, -1]\n", "p.yaml"),
               InputError);
  try {  // a record says what it is
    calib::ParsePlaneHeightsYaml("heights_mm: [1, 2]\nplate_normal_in_sensor: [0, 0, -1]\n",
                                 "p.yaml");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "field 'format' is required, expected 'lasercell.plane_heights'"),
              std::string::npos)
        << e.what();
  }
}

triangulation::ProfileSet SmallSet(std::uint32_t width, std::uint32_t height) {
  triangulation::ProfileSet set;
  set.header.image_width = width;
  set.header.image_height = height;
  set.header.first_column = 10;
  set.header.columns = 3;
  for (int k = 0; k < 2; ++k) {
    triangulation::Profile p = triangulation::Profile::Empty(3);
    p.sequence = static_cast<std::uint64_t>(k);
    p.row_px[0] = 20.25f + static_cast<float>(k);
    p.intensity[0] = 0.5f;
    p.width_px[0] = 2.0f;
    p.row_px[2] = 30.5f;
    p.intensity[2] = 0.5f;
    p.width_px[2] = 2.0f;
    set.profiles.push_back(p);
  }
  return set;
}

TEST(LaserPlaneCaptures, ValidPeaksBecomeColumnRowPixels) {
  const calib::HeightCapture c =
      triangulation::HeightCaptureFromProfiles(SmallSet(64, 48), "a.lcp", 150);
  EXPECT_EQ(c.name, "a.lcp");
  EXPECT_EQ(c.height_mm, 150);
  ASSERT_EQ(c.peaks_px.size(), 4u);  // the NaN column 11 is skipped
  EXPECT_EQ(c.peaks_px[0], Eigen::Vector2d(10, 20.25));
  EXPECT_EQ(c.peaks_px[1], Eigen::Vector2d(12, 30.5));
  EXPECT_EQ(c.peaks_px[2], Eigen::Vector2d(10, 21.25));
}

TEST(LaserPlaneCaptures, PlaneFilesAreOrderedByIndexAndCheckedAgainstTheCamera) {
  const test::TestDir dir("plane_files");
  const std::filesystem::path profiles = dir.path() / "profiles";
  std::filesystem::create_directories(profiles);
  EXPECT_THROW(triangulation::FindPlaneProfileFiles(dir.path().string()), FileError);
  for (const int i : {10, 2}) {
    triangulation::WriteProfiles((profiles / ("plane_" + std::to_string(i) + ".lcp")).string(),
                                 SmallSet(64, 48));
  }
  const std::vector<std::string> files = triangulation::FindPlaneProfileFiles(dir.path().string());
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(std::filesystem::path(files[0]).filename(), "plane_2.lcp");
  EXPECT_EQ(std::filesystem::path(files[1]).filename(), "plane_10.lcp");
  const calib::CameraModel camera("LENSMODEL_PINHOLE", {100, 100, 32, 24}, 64, 48);
  InputDigest digest;
  const auto captures = triangulation::LoadHeightCaptures(files, {150, 250}, camera, &digest);
  ASSERT_EQ(captures.size(), 2u);
  EXPECT_EQ(captures[1].height_mm, 250);
  EXPECT_EQ(captures[1].peaks_px.size(), 4u);
  EXPECT_NE(digest.Text(), InputDigest().Text());
  const calib::CameraModel other("LENSMODEL_PINHOLE", {100, 100, 32, 24}, 640, 480);
  try {
    triangulation::LoadHeightCaptures(files, {150, 250}, other);
    FAIL() << "expected FileError";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "was recorded with a 64x48 sensor but the camera model is 640x480"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lasercell
