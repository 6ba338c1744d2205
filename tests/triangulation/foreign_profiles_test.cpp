// scan_line profiles of other software (triangulation/foreign_profiles.hpp): the real
// laser_robot_sphere profiles, counted here independently of OpenCV (tokens between the
// brackets), and every malformed input naming the file and the problem.
#include "triangulation/foreign_profiles.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "tests/cli_util.hpp"
#include "tests/shared_data.hpp"

namespace lasercell::triangulation {
namespace {

// A scan_line file's counts from its text alone: the comma-separated tokens between '[' and
// ']', a triple missing when any of its tokens is `.Nan`.
struct TextCounts {
  std::size_t numbers = 0, columns = 0, missing = 0;
  std::vector<double> first_point, last_point;  // The first and last finite triples.
};

TextCounts CountScanLine(const std::string& text) {
  const std::size_t open = text.find('[', text.find("scan_line:"));
  const std::size_t close = text.find(']', open);
  std::istringstream in(text.substr(open + 1, close - open - 1));
  std::vector<std::string> tokens;
  for (std::string t; std::getline(in, t, ',');) {
    std::istringstream ts(t);
    std::string word;
    ts >> word;
    tokens.push_back(word);
  }
  TextCounts c;
  c.numbers = tokens.size();
  c.columns = tokens.size() / 3;
  for (std::size_t i = 0; i + 2 < tokens.size(); i += 3) {
    if (tokens[i] == ".Nan" || tokens[i + 1] == ".Nan" || tokens[i + 2] == ".Nan") {
      ++c.missing;
      continue;
    }
    std::vector<double> p;
    for (std::size_t k = i; k < i + 3; ++k) p.push_back(std::strtod(tokens[k].c_str(), nullptr));
    if (c.first_point.empty()) c.first_point = p;
    c.last_point = p;
  }
  return c;
}

// Reads a real profile and checks it against the counts of its text.
ScanLineProfile ExpectMatchesText(const std::string& path) {
  const TextCounts c = CountScanLine(test::Slurp(path));
  const ScanLineProfile p = ReadScanLineProfile(path);
  EXPECT_EQ(c.numbers % 3, 0u) << path;
  EXPECT_EQ(p.columns, c.columns) << path;
  EXPECT_EQ(p.missing, c.missing) << path;
  EXPECT_EQ(p.points_in_sensor.size(), c.columns - c.missing) << path;
  std::size_t off_plane = 0, non_finite = 0;
  for (const Eigen::Vector3d& q : p.points_in_sensor) {
    off_plane += q.y() != 0.0 ? 1 : 0;
    non_finite += q.allFinite() ? 0 : 1;
  }
  EXPECT_EQ(off_plane, 0u) << path;  // The files write every y as `0.`.
  EXPECT_EQ(non_finite, 0u) << path;
  if (!p.points_in_sensor.empty() && c.first_point.size() == 3) {
    const Eigen::Vector3d first(c.first_point[0], c.first_point[1], c.first_point[2]);
    const Eigen::Vector3d last(c.last_point[0], c.last_point[1], c.last_point[2]);
    EXPECT_LT((p.points_in_sensor.front() - first).norm(), 1e-9) << path;
    EXPECT_LT((p.points_in_sensor.back() - last).norm(), 1e-9) << path;
  }
  return p;
}

// Writes `text` to a file of `dir`, reads it, expects FileError naming the file and `part`.
void ExpectReadError(const test::TestDir& dir, const std::string& text, const std::string& part) {
  const std::string path = dir.File("bad.yml");
  test::Spit(path, text);
  try {
    ReadScanLineProfile(path);
    ADD_FAILURE() << "no exception for: " << text.substr(0, 80);
  } catch (const FileError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.path(), path);
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
  }
}

const char* const kHeader = "%YAML:1.0\n---\n";

TEST(ForeignProfiles, ScanLineOfTheRealSphereProfile) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty()) {
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  }
  const ScanLineProfile p = ExpectMatchesText(dir + "/p1.yml");
  EXPECT_EQ(p.points_in_sensor.size(), 2529u);
  // First triple of the file: 1.82700005e+01, 0., -1.63049793e+01.
  EXPECT_LT((p.points_in_sensor.front() - Eigen::Vector3d(18.2700005, 0, -16.3049793)).norm(),
            1e-9);
  // One chord across the sphere of radius 40 mm: shorter than its 80 mm diameter.
  const double span = p.points_in_sensor.back().x() - p.points_in_sensor.front().x();
  EXPECT_GT(span, 50.0);
  EXPECT_LT(span, 80.0);
}

TEST(ForeignProfiles, ScanLinesOfAllRealProfilesLoad) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty()) {
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  }
  const ScanLineProfile ball7 = ExpectMatchesText(dir + "/ball/7_3C_line.yml");
  EXPECT_EQ(ball7.columns, 2048u);
  EXPECT_GT(ball7.missing, 0u);
  EXPECT_GT(ball7.points_in_sensor.size(), 0u);
  const ScanLineProfile ball1 = ExpectMatchesText(dir + "/ball/1_3C_line.yml");
  EXPECT_EQ(ball1.columns, 2048u);
  for (int i = 1; i <= 15; ++i) ExpectMatchesText(dir + "/p" + std::to_string(i) + ".yml");
  for (int i = 1; i <= 12; ++i) {
    ExpectMatchesText(dir + "/board/" + std::to_string(i) + "_3C_line.yml");
  }
}

TEST(ForeignProfiles, ScanLineNanTriplesAreMissingAndOrderIsKept) {
  const test::TestDir dir("foreign_profiles");
  const std::string path = dir.File("p.yml");
  test::Spit(path, std::string(kHeader) +
                       "scan_line: [ 1., 0., 2., .Nan, 0., .Nan, 3, 0., 4.,\n"
                       "    -5.5, 0., .Nan, 6., 1e-4, -7. ]\nother: 3\n");
  const ScanLineProfile p = ReadScanLineProfile(path);
  EXPECT_EQ(p.columns, 5u);
  EXPECT_EQ(p.missing, 2u);
  ASSERT_EQ(p.points_in_sensor.size(), 3u);
  EXPECT_EQ(p.points_in_sensor[0], Eigen::Vector3d(1, 0, 2));
  EXPECT_EQ(p.points_in_sensor[1], Eigen::Vector3d(3, 0, 4));
  EXPECT_EQ(p.points_in_sensor[2], Eigen::Vector3d(6, 1e-4, -7));
}

TEST(ForeignProfiles, ScanLineErrorsNameFileAndProblem) {
  const test::TestDir dir("foreign_profiles");
  const std::string h = kHeader;
  ExpectReadError(dir, h + "other: [ 1., 0., 2. ]\n", "no `scan_line` key");
  ExpectReadError(dir, h + "scan_line: [ 1., 0., 2., 3. ]\n", "4 numbers, not a multiple of 3");
  ExpectReadError(dir, h + "scan_line: [ 1., 0., 2., 3., 0.5, 4. ]\n",
                  "`scan_line` point 2: not a profile in the laser plane: y = 0.5 mm");
  ExpectReadError(dir, h + "scan_line: [ 1., 0., 2., 3., 0., .Inf ]\n",
                  "`scan_line` point 2: infinite value");
  ExpectReadError(dir, h + "scan_line: [ .Nan, 0., .Nan, 3., 0., .Nan ]\n",
                  "no finite point: all 2 columns are NaN");
  ExpectReadError(dir, h + "scan_line: []\n", "`scan_line` is empty");
  ExpectReadError(dir, h + "scan_line: [ 1., 0., two ]\n", "element 3 is not a number");
  ExpectReadError(dir, h + "scan_line: [ 1., 0., [ 2. ] ]\n", "element 3 is not a number");
  ExpectReadError(dir, h + "scan_line: 5\n", "`scan_line` is not a sequence of numbers");
  ExpectReadError(dir, h + "scan_line: [ 1., 0., 2.\n", "not readable as OpenCV FileStorage");
  ExpectReadError(dir, "hello\x01\x02 world: [\n", "not readable as OpenCV FileStorage");
  ExpectReadError(dir, "scan_line: [ 1., 0., 2. ]\n", "'%YAML:1.0'");
  ExpectReadError(dir, "  \n", "empty file");
  try {
    ReadScanLineProfile(dir.File("absent.yml"));
    ADD_FAILURE() << "no exception for a missing file";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), dir.File("absent.yml"));
  }
}

}  // namespace
}  // namespace lasercell::triangulation
