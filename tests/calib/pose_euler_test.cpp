// Robot poses as x y z + three Euler angles (calib/pose_io.hpp formats xyzwpr and xyzabc): the
// Fanuc and KUKA rotations against hand-computed matrices and Eigen angle-axis products, both
// layouts (text lines, RobCalibrator's RobPoses JSON), the real laser_robot_sphere pose files,
// "auto" refusing to guess the convention, and every malformed input naming file and place.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <functional>
#include <string>
#include <vector>

#include "calib/pose_io.hpp"
#include "core/error.hpp"
#include "tests/cli_util.hpp"
#include "tests/shared_data.hpp"

namespace lasercell::calib {
namespace {

constexpr double kDeg = EIGEN_PI / 180.0;

Eigen::Matrix3d Rx(double deg) {
  return Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
Eigen::Matrix3d Ry(double deg) {
  return Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
}
Eigen::Matrix3d Rz(double deg) {
  return Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// The single pose of a one-line text.
Eigen::Isometry3d OnePose(const std::string& line, EulerConvention convention) {
  const RobotPoses p = ParseEulerPoses(line + "\n", "one.txt", convention);
  EXPECT_EQ(p.base_from_flange.size(), 1u);
  return p.base_from_flange.at(0);
}

// Runs `parse`, expects a FileError whose message starts with `name` and holds every part.
void ExpectFileError(const std::function<void()>& parse, const std::string& name,
                     const std::vector<std::string>& parts) {
  try {
    parse();
    ADD_FAILURE() << "no exception; expected one mentioning " << parts.front();
  } catch (const FileError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(name + ": ", 0), 0u) << what;
    EXPECT_EQ(e.path(), name);
    for (const std::string& part : parts) {
      EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
    }
  }
}

void ExpectEulerError(const std::string& text, EulerConvention convention,
                      const std::vector<std::string>& parts) {
  ExpectFileError([&] { ParseEulerPoses(text, "bad.rob", convention); }, "bad.rob", parts);
}

constexpr auto kFanuc = EulerConvention::kFanucXyzwpr;
constexpr auto kKuka = EulerConvention::kKukaXyzabc;

TEST(PoseEuler, FanucSingleAnglesAreHandComputed) {
  Eigen::Matrix3d rx90;  // w = 90: about base x, y -> z
  rx90 << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  Eigen::Matrix3d ry90;  // p = 90: z -> x
  ry90 << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  Eigen::Matrix3d rz90;  // r = 90: x -> y
  rz90 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Isometry3d w = OnePose("100 -200 300 90 0 0", kFanuc);
  EXPECT_TRUE(w.linear().isApprox(rx90, 1e-12)) << w.linear();
  EXPECT_TRUE(w.translation().isApprox(Eigen::Vector3d(100, -200, 300), 1e-12));
  EXPECT_TRUE(OnePose("100 -200 300 0 90 0", kFanuc).linear().isApprox(ry90, 1e-12));
  EXPECT_TRUE(OnePose("100 -200 300 0 0 90", kFanuc).linear().isApprox(rz90, 1e-12));
}

TEST(PoseEuler, FanucMixedIsRzRyRx) {
  const Eigen::Isometry3d p = OnePose("500, 20, 700, 10, -20, 30", kFanuc);
  const Eigen::Matrix3d expected = Rz(30) * Ry(-20) * Rx(10);
  EXPECT_LT((p.linear() - expected).norm(), 1e-12) << p.linear();
  // The other order differs by far more than the tolerance: the test sees a swapped product.
  EXPECT_GT((p.linear() - Rx(10) * Ry(-20) * Rz(30)).norm(), 0.05);
  const Eigen::Isometry3d big = OnePose("500 20 700 -179.924 0.889 179.635", kFanuc);
  EXPECT_LT((big.linear() - Rz(179.635) * Ry(0.889) * Rx(-179.924)).norm(), 1e-12);
}

TEST(PoseEuler, KukaAbcIsRzRyRxWithAFirst) {
  Eigen::Matrix3d rz90;
  rz90 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  Eigen::Matrix3d rx90;
  rx90 << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  EXPECT_TRUE(OnePose("100 200 300 90 0 0", kKuka).linear().isApprox(rz90, 1e-12));
  EXPECT_TRUE(OnePose("100 200 300 0 0 90", kKuka).linear().isApprox(rx90, 1e-12));
  const Eigen::Isometry3d p = OnePose("500 20 700 30 -20 10", kKuka);
  EXPECT_LT((p.linear() - Rz(30) * Ry(-20) * Rx(10)).norm(), 1e-12) << p.linear();
  // KUKA A B C lists the Fanuc w p r angles in reverse: the same rotation.
  EXPECT_LT((p.linear() - OnePose("500 20 700 10 -20 30", kFanuc).linear()).norm(), 1e-12);
  EXPECT_GT((p.linear() - OnePose("500 20 700 30 -20 10", kFanuc).linear()).norm(), 0.05);
}

TEST(PoseEuler, ConventionNamesSayTheProduct) {
  EXPECT_NE(EulerConventionName(kFanuc).find("xyzwpr"), std::string::npos);
  EXPECT_NE(EulerConventionName(kFanuc).find("Rz(r) Ry(p) Rx(w)"), std::string::npos);
  EXPECT_NE(EulerConventionName(kKuka).find("xyzabc"), std::string::npos);
  EXPECT_NE(EulerConventionName(kKuka).find("Rz(A) Ry(B) Rx(C)"), std::string::npos);
}

TEST(PoseEuler, TextSkipsCommentsAndBlankLinesAndJsonGivesTheSamePoses) {
  const std::string text =
      "# x y z w p r\n\n 100, 200, 300, 90, 0, 0\r\n   \n# next\n-100\t50 400 0 0 -45";
  const RobotPoses t = ParseEulerPoses(text, "p.txt", kFanuc);
  const std::string json =
      "  \n{ \"RobPoses\": [ [100, 200, 300, 90, 0, 0],\n [-100, 50, 400.0, 0, 0, -45] ] }\n";
  const RobotPoses j = ParseEulerPoses(json, "p.rob", kFanuc);
  ASSERT_EQ(t.base_from_flange.size(), 2u);
  ASSERT_EQ(j.base_from_flange.size(), 2u);
  EXPECT_TRUE(t.images.empty());
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_TRUE(t.base_from_flange[i].matrix().isApprox(j.base_from_flange[i].matrix(), 1e-12));
  }
  EXPECT_TRUE(t.base_from_flange[1].linear().isApprox(Rz(-45), 1e-12));
  EXPECT_TRUE(t.base_from_flange[1].translation().isApprox(Eigen::Vector3d(-100, 50, 400)));
}

TEST(PoseEuler, RealRobCalibratorJsonHasFifteenPoses) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty()) {
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  }
  const RobotPoses p = LoadRobotPoses(dir + "/RobPoses.rob", "xyzwpr");
  ASSERT_EQ(p.base_from_flange.size(), 15u);
  EXPECT_LT(
      (p.base_from_flange[0].translation() - Eigen::Vector3d(-195.8, 1363.305, 524.812)).norm(),
      1e-9);
  EXPECT_LT((p.base_from_flange[0].linear() - Rz(179.635) * Ry(0.889) * Rx(-179.924)).norm(),
            1e-12);
  // The last pose: -12.159 1349.104 524.655 -179.918 0.888 -165.374.
  EXPECT_LT((p.base_from_flange[14].linear() - Rz(-165.374) * Ry(0.888) * Rx(-179.918)).norm(),
            1e-12);
  EXPECT_NEAR(p.base_from_flange[14].translation().x(), -12.159, 1e-9);
}

TEST(PoseEuler, RealTextPoseFilesLoad) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty()) {
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  }
  const RobotPoses ball = LoadRobotPoses(dir + "/ball/robpose.txt", "xyzwpr");
  ASSERT_EQ(ball.base_from_flange.size(), 10u);
  // First line: 545.368 295.958 20.698 -179.825 -2.819 45.415.
  EXPECT_LT(
      (ball.base_from_flange[0].translation() - Eigen::Vector3d(545.368, 295.958, 20.698)).norm(),
      1e-9);
  EXPECT_LT((ball.base_from_flange[0].linear() - Rz(45.415) * Ry(-2.819) * Rx(-179.825)).norm(),
            1e-12);
  // rob2board.txt has no newline after its last line.
  EXPECT_EQ(LoadRobotPoses(dir + "/board/rob2board.txt", "xyzwpr").base_from_flange.size(), 12u);
  EXPECT_EQ(LoadRobotPoses(dir + "/ball/robpose.txt", "xyzabc").base_from_flange.size(), 10u);
}

TEST(PoseEuler, AutoRefusesRealEulerFiles) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty()) {
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  }
  for (const std::string file : {"/RobPoses.rob", "/ball/robpose.txt", "/board/rob2board.txt"}) {
    ExpectFileError([&] { LoadRobotPoses(dir + file, "auto"); }, dir + file,
                    {"does not state its Euler convention", "xyzwpr", "xyzabc"});
  }
}

TEST(PoseEuler, AutoRefusesBothLayoutsAndKeepsKukaAndYaml) {
  const test::TestDir dir("pose_euler");
  const std::string json = dir.File("poses.rob");
  test::Spit(json, "{\"RobPoses\": [[100, 200, 300, 0, 0, 0]]}\n");
  ExpectFileError([&] { LoadRobotPoses(json); }, json,
                  {"RobPoses JSON", "does not state its Euler convention", "xyzwpr for Fanuc",
                   "xyzabc for KUKA"});
  const std::string text = dir.File("poses.txt");
  test::Spit(text, "# robot\n100 200 300 0 0 0\n110 200 300 0 0 0\n");
  ExpectFileError([&] { LoadRobotPoses(text, "auto"); }, text,
                  {"lines of 6 numbers", "does not state its Euler convention"});
  EXPECT_EQ(LoadRobotPoses(text, "xyzwpr").base_from_flange.size(), 2u);
  EXPECT_EQ(LoadRobotPoses(json, "xyzabc").base_from_flange.size(), 1u);
  // Unchanged: 16 numbers in metres are kuka, a `format:` key is yaml.
  const std::string kuka = dir.File("kuka.txt");
  test::Spit(kuka, "1 0 0 0.5 0 1 0 -0.25 0 0 1 1.125 0 0 0 1\n");
  const RobotPoses k = LoadRobotPoses(kuka);
  ASSERT_EQ(k.base_from_flange.size(), 1u);
  EXPECT_TRUE(k.base_from_flange[0].translation().isApprox(Eigen::Vector3d(500, -250, 1125)));
  const std::string yaml = dir.File("poses.yaml");
  test::Spit(yaml, RobotPosesYaml(k));
  EXPECT_EQ(LoadRobotPoses(yaml).base_from_flange.size(), 1u);
}

TEST(PoseEuler, UnknownFormatListsTheValidOnes) {
  const test::TestDir dir("pose_euler");
  const std::string text = dir.File("poses.txt");
  test::Spit(text, "100 200 300 0 0 0\n");
  try {
    LoadRobotPoses(text, "xyzrpy");
    FAIL() << "no exception";
  } catch (const OptionError& e) {
    const std::string what = e.what();
    for (const char* f : {"kuka", "yaml", "xyzwpr", "xyzabc", "auto", "'xyzrpy'"}) {
      EXPECT_NE(what.find(f), std::string::npos) << what;
    }
  }
}

TEST(PoseEuler, TextErrorsNameTheLine) {
  ExpectEulerError("100 200 300 0 0 0\n100 200 300 0 0\n", kFanuc,
                   {"line 2: expected 6 numbers", "got 5", "xyzwpr"});
  ExpectEulerError("100 200 300 0 0 0 7\n", kKuka, {"line 1: expected 6 numbers", "got 7"});
  ExpectEulerError("# c\n100 200 300 0 zero 0\n", kFanuc, {"line 2: 'zero' is not a number"});
  ExpectEulerError("100 200 300 0 nan 0\n", kFanuc, {"line 1: p is not a finite number"});
  ExpectEulerError("100 200 inf 0 0 0\n", kKuka, {"line 1: z is not a finite number"});
  ExpectEulerError("\n100 200 300 0 0 0\n100 200 300 0 0 400\n", kFanuc,
                   {"line 3: angle r = 400", "angles must be degrees"});
  ExpectEulerError("100 200 300 -361 0 0\n", kKuka, {"angle A = -361", "angles must be degrees"});
  ExpectEulerError("1 0 0 0.5 0 1 0 -0.25 0 0 1 1.125 0 0 0 1\n", kFanuc,
                   {"got 16", "use the kuka format"});
}

TEST(PoseEuler, NoPosesAndMetresAreRejected) {
  ExpectEulerError("# nothing\n\n", kFanuc, {"no poses"});
  ExpectEulerError("", kKuka, {"no poses"});
  ExpectEulerError("{\"RobPoses\": []}", kFanuc, {"no poses"});
  ExpectEulerError("0.5 0.2 0.9 0 0 0\n0.6 0.2 0.9 0 0 0\n", kFanuc, {"look like metres"});
  ExpectEulerError("0.5 0.2 0.9 0 0 0\n600 200 900 0 0 0\n", kFanuc, {"mixed units"});
}

TEST(PoseEuler, JsonErrorsNameThePose) {
  ExpectEulerError("{\"RobPoses\": [[100, 200, 300, 0, 0, 0]], \"Tool\": 1}", kFanuc,
                   {"unknown key \"Tool\"", "RobPoses"});
  ExpectEulerError("{\"Poses\": [[100, 200, 300, 0, 0, 0]]}", kFanuc, {"unknown key \"Poses\""});
  ExpectEulerError("{}", kFanuc, {"\"RobPoses\" must be a list"});
  ExpectEulerError("{\"RobPoses\": 5}", kFanuc, {"\"RobPoses\" must be a list"});
  ExpectEulerError("{\"RobPoses\": [[100, 200, 300, 0, 0, 0], [100, 200, 300, 0, 0]]}", kFanuc,
                   {"pose 2 (RobPoses[1]): expected 6 numbers", "[100,200,300,0,0]"});
  ExpectEulerError("{\"RobPoses\": [[100, 200, 300, 0, 0, \"0\"]]}", kKuka,
                   {"pose 1 (RobPoses[0]): expected 6 numbers", "xyzabc"});
  ExpectEulerError("{\"RobPoses\": [[100, 200, 300, 0, 0, 0], 7]}", kFanuc,
                   {"pose 2 (RobPoses[1]): expected 6 numbers"});
  ExpectEulerError(
      "{\"RobPoses\": [[100, 200, 300, 0, 0, 0], [1, 2, 300, 0, 0, 0], [100, 200, 300, 0, "
      "720, 0]]}",
      kFanuc, {"pose 3 (RobPoses[2]): angle p = 720", "angles must be degrees"});
  ExpectEulerError("{\"RobPoses\": [[100, 200, 300, 0, 0, 0]", kFanuc, {"not valid JSON"});
  ExpectEulerError("[[100, 200, 300, 0, 0, 0]]", kFanuc, {"'[[100' is not a number"});
}

}  // namespace
}  // namespace lasercell::calib
