// `lasercell calibrate handeye-laser --profiles ... --poses ...` as a user runs it on the real
// AT C5 / Fanuc sphere set: the JSON, the updated cell (re-read), and one-line refusals (exit 2)
// for what a user gets wrong with foreign files.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/frame_graph.hpp"
#include "tests/cli_util.hpp"
#include "tests/shared_data.hpp"

namespace lasercell {
namespace {

using test::RunCliMerged;
namespace fs = std::filesystem;

std::string ProfileArgs(const std::string& dir, int count) {
  std::string args = " --profiles";
  for (int i = 1; i <= count; ++i) args += " '" + dir + "/p" + std::to_string(i) + ".yml'";
  return args;
}

TEST(SphereSectionCli, RealSetWritesJsonAndUpdatesTheCell) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty())
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  const fs::path tmp =
      fs::temp_directory_path() / ("lasercell_sections_" + std::to_string(getpid()));
  fs::create_directories(tmp);
  const std::string cell_in = std::string(LASERCELL_SOURCE_DIR) + "/datasets/demo/cell.yaml";
  const std::string common = ProfileArgs(dir, 15) + " --poses '" + dir +
                             "/RobPoses.rob' --pose-format xyzwpr --sphere-side -y "
                             "--sphere-radius 40";
  const auto run =
      RunCliMerged("calibrate handeye-laser" + common + " --cell '" + cell_in + "' --output '" +
                   (tmp / "cell.yaml").string() + "' --json '" + (tmp / "r.json").string() +
                   "' --report '" + (tmp / "r.html").string() + "'");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nlohmann::json j = nlohmann::json::parse(test::Slurp(tmp / "r.json"));
  EXPECT_EQ(j["format"], "lasercell.laser_hand_eye_sections");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["sections_used"], 15);
  EXPECT_LE(j["centre_spread_mm"]["rms"].get<double>(), 0.3);
  EXPECT_EQ(j["sections"].size(), 15u);
  EXPECT_TRUE(j["leave_one_out"]["rms_mm"].is_number());
  EXPECT_NE(test::Slurp(tmp / "r.html").find("<table"), std::string::npos);
  // The cell keeps everything else and now holds the calibrated edge, as the JSON says.
  const FrameGraph cell = LoadFrameGraph((tmp / "cell.yaml").string());
  const Eigen::Isometry3d x = cell.Transform("vision_flange", "sensor");
  const auto& t = j["flange_from_sensor"]["translation_mm"];
  EXPECT_NEAR(x.translation().x(), t[0].get<double>(), 1e-6);
  EXPECT_NEAR(x.translation().y(), t[1].get<double>(), 1e-6);
  EXPECT_NEAR(x.translation().z(), t[2].get<double>(), 1e-6);
  EXPECT_NO_THROW(cell.Transform("handling_base", "vision_base"));
  fs::remove_all(tmp);
}

TEST(SphereSectionCli, RefusesWhatItCannotKnow) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty())
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  const std::string poses = " --poses '" + dir + "/RobPoses.rob'";
  const fs::path never = fs::temp_directory_path() /
                         ("lasercell_sections_refused_" + std::to_string(getpid()) + ".json");
  const std::string rest = " --sphere-radius 40 --json '" + never.string() + "'";
  // The Euler convention is not in the file: never guessed.
  auto r = RunCliMerged("calibrate handeye-laser" + ProfileArgs(dir, 15) + poses +
                        " --pose-format auto --sphere-side -y" + rest);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("does not state its Euler convention"), std::string::npos) << r.out;
  // The side of the plane is not in one profile.
  r = RunCliMerged("calibrate handeye-laser" + ProfileArgs(dir, 15) + poses +
                   " --pose-format xyzwpr --sphere-side up" + rest);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--sphere-side must be +y or -y"), std::string::npos) << r.out;
  // One profile per pose.
  r = RunCliMerged("calibrate handeye-laser" + ProfileArgs(dir, 14) + poses +
                   " --pose-format xyzwpr --sphere-side -y" + rest);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("14 profiles but 15 poses"), std::string::npos) << r.out;
  // A pose file given as the 15th profile.
  r = RunCliMerged("calibrate handeye-laser" + ProfileArgs(dir, 14) + " '" + dir +
                   "/RobPoses.rob'" + poses + " --pose-format xyzwpr --sphere-side -y" + rest);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("RobPoses.rob: "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("profiles but"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(never)) << "a refused run wrote its result";
}

}  // namespace
}  // namespace lasercell
