// Job files (localize/job.hpp): every field arrives, bad fields name the file and the field.
#include "localize/job.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::localize {
namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

class JobFile : public ::testing::Test {
 protected:
  void SetUp() override {
    io::WriteFileAtomically(dir_.File("seat.part.yaml"),
                            "format: lasercell.part\nversion: 1\nname: seat\nmodel: seat.stl\n"
                            "units: mm\n");
    io::WriteFileAtomically(dir_.File("back.part.yaml"),
                            "format: lasercell.part\nversion: 1\nname: back\nmodel: back.stl\n"
                            "units: mm\n");
  }
  std::string Path() const { return dir_.File("job.yaml"); }
  Job Parse(const std::string& text) const { return ParseJobFile(text, Path()); }
  std::string Error(const std::string& text) const {
    return ErrorOf([&] { Parse(text); });
  }
  test::TestDir dir_{"job_file"};
};

constexpr const char* kHead =
    "format: lasercell.job\nversion: 1\ncell: cal/cell.yaml\ncamera: cal/camera.cameramodel\n"
    "source: {file: seat.lcp}\n";

TEST_F(JobFile, EveryFieldArrives) {
  const Job job = Parse(std::string(kHead) +
                        "laser: laser_2\n"
                        "trajectory: {linear: records/linear_sweep.yaml}\n"
                        "target_frame: cell\n"
                        "roi: {min_mm: [-300, -300, -50], max_mm: [300, 300, 200]}\n"
                        "support_plane: {normal: [0, 0, 1], offset_mm: 12.5, "
                        "max_penetration_mm: 2}\n"
                        "parts:\n  - {part: seat.part.yaml, instances: 2}\n"
                        "  - {part: back.part.yaml}\n"
                        "grasp_tolerance_mm: 8\nscan_noise_mm: 0.05\nmax_rmse_factor: 4\n"
                        "threads: 1\nmodel_cache: cache\n"
                        "localize: {max_verified_clusters: 7, icp: {max_iterations: 12}}\n");
  const std::string folder = dir_.path().string();
  EXPECT_EQ(job.cell, folder + "/cal/cell.yaml");
  EXPECT_EQ(job.camera, folder + "/cal/camera.cameramodel");
  EXPECT_EQ(job.laser, "laser_2");
  EXPECT_EQ(job.profiles, folder + "/seat.lcp");
  EXPECT_EQ(job.linear_record, folder + "/records/linear_sweep.yaml");
  EXPECT_FALSE(job.robot_trajectory);
  EXPECT_EQ(job.target_frame, "cell");
  ASSERT_TRUE(job.use_roi);
  EXPECT_EQ(job.roi.min, Eigen::Vector3d(-300, -300, -50));
  EXPECT_EQ(job.roi.max, Eigen::Vector3d(300, 300, 200));
  ASSERT_TRUE(job.support.enabled);
  EXPECT_EQ(job.support.offset_mm, 12.5);
  EXPECT_EQ(job.support.max_penetration_mm, 2.0);
  ASSERT_EQ(job.parts.size(), 2u);
  EXPECT_EQ(job.parts[0].part.name, "seat");
  EXPECT_EQ(job.parts[0].instances, 2);
  EXPECT_EQ(job.parts[1].part.name, "back");
  EXPECT_EQ(job.parts[1].instances, 1);
  EXPECT_EQ(job.grasp_tolerance_mm, 8.0);
  EXPECT_EQ(job.scan_noise_mm, 0.05);
  EXPECT_EQ(job.max_rmse_factor, 4.0);
  EXPECT_EQ(job.threads, 1);
  EXPECT_EQ(job.model_cache, folder + "/cache");
  EXPECT_EQ(job.settings.localize.max_verified_clusters, 7u);
  EXPECT_EQ(job.settings.localize.icp.max_iterations, 12);

  const Job robot = Parse(std::string(kHead) +
                          "trajectory: {robot: vision_robot}\n"
                          "parts: [{part: seat.part.yaml}]\n");
  EXPECT_TRUE(robot.robot_trajectory);
  EXPECT_EQ(robot.robot, "vision_robot");
  EXPECT_EQ(robot.target_frame, "handling_base");  // the default
  EXPECT_FALSE(robot.use_roi);
  EXPECT_EQ(robot.grasp_tolerance_mm, 10.0);  // the paper's gripper
}

TEST_F(JobFile, UnknownMissingOrBadFieldsNameTheFileAndTheField) {
  const std::string parts = "parts: [{part: seat.part.yaml}]\n";
  const std::string linear = "trajectory: {linear: l.yaml}\n";
  EXPECT_NE(Error(std::string(kHead) + linear + parts + "gripper: 3\n").find("gripper"),
            std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + parts).find("field 'trajectory' is required"),
            std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + linear).find("field 'parts' is required"),
            std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + linear + "parts: []\n").find("is empty"), std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + "trajectory: {linear: l.yaml, robot: r}\n" + parts)
                .find("exactly one of"),
            std::string::npos);
  EXPECT_NE(
      Error(std::string(kHead) + linear + parts + "roi: {min_mm: [0, 0, 0], max_mm: [10, 0, 10]}\n")
          .find("the box is empty along y"),
      std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + linear + parts + "support_plane: {normal: [0, 0, 2]}\n")
                .find("unit vector"),
            std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + linear + "parts: [{part: missing.part.yaml}]\n")
                .find("missing.part.yaml"),
            std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + linear +
                  "parts: [{part: seat.part.yaml}, "
                  "{part: seat.part.yaml}]\n")
                .find("a second time"),
            std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + linear + parts + "grasp_tolerance_mm: 0\n")
                .find("grasp_tolerance_mm"),
            std::string::npos);
  EXPECT_NE(Error(std::string(kHead) + linear + parts + "localize: {icp: {max_iterations: 0}}\n")
                .find("max_iterations"),
            std::string::npos);
  EXPECT_NE(Error("format: lasercell.part\nversion: 1\n").find("expected 'lasercell.job'"),
            std::string::npos);
  EXPECT_NE(Error("format: lasercell.job\n").find("field 'version' is required"),
            std::string::npos);
  const std::string e = Error(std::string(kHead) + linear + parts + "threads: -1\n");
  EXPECT_EQ(e.rfind(Path(), 0), 0u) << e;  // the message starts with the file
}

}  // namespace
}  // namespace lasercell::localize
