#include "triangulation/sphere_sweeps.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "datasets/cell.hpp"
#include "datasets/simulate.hpp"
#include "tests/cli_util.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/sweep.hpp"

namespace lasercell::triangulation {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

SphereSweepList TwoSets() {
  SphereSweepList list;
  list.sets.push_back(
      {"eye_in_hand", {{"profiles/eye_in_hand_00.lcp", 0}, {"profiles/eye_in_hand_01.lcp", 1}}});
  list.sets.push_back({"joint_poses", {{"profiles/joint_pose_000.lcp", 3}}});
  return list;
}

TEST(SphereSweepList, WriterTextIsTheRecordsFile) {
  EXPECT_EQ(SphereSweepListYaml(TwoSets()),
            "format: lasercell.sphere_sweeps\nversion: 1\n"
            "# Pose-sweep sets of the vision robot (joints in each profile).\n"
            "eye_in_hand:\n"
            "  - {profiles_file: profiles/eye_in_hand_00.lcp, aimed_at_sphere: 0}\n"
            "  - {profiles_file: profiles/eye_in_hand_01.lcp, aimed_at_sphere: 1}\n"
            "joint_poses:\n"
            "  - {profiles_file: profiles/joint_pose_000.lcp, aimed_at_sphere: 3}\n");
}

TEST(SphereSweepList, RoundTripsThroughTheReader) {
  const SphereSweepList in = TwoSets();
  const SphereSweepList out = ParseSphereSweepList(SphereSweepListYaml(in), "list.yaml");
  ASSERT_EQ(out.sets.size(), in.sets.size());
  for (std::size_t s = 0; s < in.sets.size(); ++s) {
    EXPECT_EQ(out.sets[s].name, in.sets[s].name);
    ASSERT_EQ(out.sets[s].sweeps.size(), in.sets[s].sweeps.size());
    for (std::size_t i = 0; i < in.sets[s].sweeps.size(); ++i) {
      EXPECT_EQ(out.sets[s].sweeps[i].profiles_file, in.sets[s].sweeps[i].profiles_file);
      EXPECT_EQ(out.sets[s].sweeps[i].aimed_at_sphere, in.sets[s].sweeps[i].aimed_at_sphere);
    }
  }
  EXPECT_EQ(SphereSweepListYaml(out), SphereSweepListYaml(in));
  ASSERT_NE(out.Find("joint_poses"), nullptr);
  EXPECT_EQ(out.Find("nope"), nullptr);
}

TEST(SphereSweepList, ReaderIsStrict) {
  const std::string head = "format: lasercell.sphere_sweeps\nversion: 1\n";
  EXPECT_THAT(
      [&] {
        ParseSphereSweepList(head + "s:\n  - {profiles_fil: a.lcp, aimed_at_sphere: 0}\n", "l");
      },
      testing::ThrowsMessage<OptionError>(HasSubstr("s[0].profiles_fil")));
  EXPECT_THAT([&] { ParseSphereSweepList(head + "s:\n  - {profiles_file: a.lcp}\n", "l"); },
              testing::ThrowsMessage<OptionError>(HasSubstr("aimed_at_sphere' is required")));
  EXPECT_THAT(
      [&] {
        ParseSphereSweepList(head + "s:\n  - {profiles_file: a.lcp, aimed_at_sphere: x}\n", "l");
      },
      testing::ThrowsMessage<OptionError>(HasSubstr("s[0].aimed_at_sphere")));
  EXPECT_THAT(
      [&] {
        ParseSphereSweepList(head + "s:\n  - {profiles_file: a.lcp, aimed_at_sphere: -1}\n", "l");
      },
      testing::ThrowsMessage<OptionError>(HasSubstr(">= 0")));
  EXPECT_THAT([&] { ParseSphereSweepList(head + "s: 3\n", "l"); },
              testing::ThrowsMessage<OptionError>(HasSubstr("non-empty list")));
  EXPECT_THAT([&] { ParseSphereSweepList("version: 1\ns: []\n", "l"); },
              testing::ThrowsMessage<OptionError>(HasSubstr("'format' is required")));
  EXPECT_THAT([&] { ParseSphereSweepList("format: lasercell.touches\nversion: 1\n", "l"); },
              testing::ThrowsMessage<OptionError>(HasSubstr("lasercell.sphere_sweeps")));
}

// The simulator renders through a calib::CameraModel, the one the sweeps are triangulated with.
calib::CameraModel SimCamera(const datasets::SensorModel& sensor) { return sensor.camera; }

// The sweep loader and `scan triangulate --exact` (AssembleSweep, exact path, sensor frame)
// turn the same profile file into the same points, bit for bit.
// Simulation profile: ideal (SimConfig{}, three eye-in-hand sweeps only).
TEST(SphereSweeps, SamePointsAsScanTriangulate) {
  datasets::SimConfig config;
  config.capture_planes = config.capture_spheres = config.capture_seats = false;
  config.capture_trajectory = config.capture_chessboard_images = false;
  config.capture_laser_line_images = config.write_meshes = false;
  config.capture_joint_poses = config.capture_touches = false;
  config.capture_hand_eye_images = false;
  config.eye_in_hand.poses = 3;
  config.eye_in_hand.profiles = 8;
  const test::TestDir scratch("sphere_sweeps");
  const fs::path dir = scratch.path();
  datasets::SimulateCell(config, dir.string(), {}, 1);
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const calib::CameraModel camera = SimCamera(truth.sensor);
  const Eigen::Vector4d plane = truth.sensor.laser.Coefficients();
  const std::string list = (dir / "records/sphere_sweeps.yaml").string();
  const std::vector<calib::SphereSweep> sweeps =
      LoadSphereSweeps(list, "eye_in_hand", camera, plane);
  ASSERT_EQ(sweeps.size(), 3u);
  const Triangulator tri(camera, plane);
  SweepOptions o;
  o.path = TriangulationPath::kExact;
  std::size_t total = 0;
  for (const calib::SphereSweep& s : sweeps) {
    const SweepResult scan = AssembleSweep(ReadProfiles((dir / s.name).string()), tri, o);
    std::vector<Eigen::Vector3d> loaded;
    for (const calib::SweptProfile& p : s.profiles) {
      EXPECT_EQ(p.joints_rad.size(), 6u);
      loaded.insert(loaded.end(), p.points_in_sensor.begin(), p.points_in_sensor.end());
    }
    ASSERT_EQ(loaded.size(), scan.cloud.positions.size()) << s.name;
    for (std::size_t i = 0; i < loaded.size(); ++i) {
      ASSERT_EQ(loaded[i], scan.cloud.positions[i]) << s.name << " point " << i;
    }
    total += loaded.size();
  }
  EXPECT_GT(total, 100u);
  EXPECT_THAT([&] { LoadSphereSweeps(list, "nope", camera, plane); },
              testing::ThrowsMessage<FileError>(HasSubstr("has no sweep set 'nope'")));
}

}  // namespace
}  // namespace lasercell::triangulation
