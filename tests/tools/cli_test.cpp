// End-to-end tests of the `lasercell` command line: exit codes (0 ok, 2 bad input, 1 internal),
// one-line error messages naming the file, and that failed commands write nothing.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/point_cloud_io.hpp"
#include "tests/cli_util.hpp"

// In lasercell::test: the shared helpers of tests/cli_util.hpp (RunCli, Slurp, ...) by name.
namespace lasercell::test {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTestDir("cli"); }
  void TearDown() override { RemoveTestDir(dir_); }

  static std::string Data(const std::string& rel) {
    return std::string(LASERCELL_SOURCE_DIR) + "/datasets/" + rel;
  }

  fs::path dir_;
};

int CountLines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

TEST_F(CliTest, VersionAndHelp) {
  CommandResult r = RunCli("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("lasercell " LASERCELL_VERSION));
  for (const char* cmd : {"--help", "cloud --help", "cloud info --help", "cloud convert --help",
                          "frames --help", "frames show --help", "frames get --help"}) {
    r = RunCli(cmd);
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_THAT(r.out, HasSubstr("Usage")) << cmd;
  }
}

TEST_F(CliTest, NoSubcommandIsBadInput) {
  CommandResult r = RunCli("");
  EXPECT_EQ(r.exit_code, 2);
  r = RunCli("cloud frobnicate");
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(CliTest, CloudInfoOnRealPly) {
  const CommandResult r = RunCli("cloud info " + Data("real/uwa/parasaurolophus_6700.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("points: 6700"));
  EXPECT_THAT(r.out, HasSubstr("fields: x y z nx ny nz"));
  EXPECT_THAT(r.out, HasSubstr("organized: no"));
  EXPECT_THAT(r.out, HasSubstr("bounding box min"));
  EXPECT_THAT(r.out, HasSubstr("millimetres"));
}

TEST_F(CliTest, CloudInfoOnOrganizedPcdReportsGridAndMetres) {
  const CommandResult r =
      RunCli("cloud info " + Data("real/pcl/milk_cartoon_all_small_clorox.pcd"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("organized: yes, 480 rows x 640 columns"));
  EXPECT_THAT(r.out, HasSubstr("metres"));
}

TEST_F(CliTest, ConvertPlyToPcdAndBackKeepsPoints) {
  const std::string pcd = (dir_ / "model.pcd").string();
  const std::string ply = (dir_ / "model.ply").string();
  CommandResult r =
      RunCli("cloud convert " + Data("real/uwa/parasaurolophus_6700.ply") + " " + pcd);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunCli("cloud convert " + pcd + " " + ply);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto original = lasercell::io::ReadPointCloud(Data("real/uwa/parasaurolophus_6700.ply"));
  const auto back = lasercell::io::ReadPointCloud(ply);
  ASSERT_EQ(back.size(), original.size());
  ASSERT_TRUE(back.HasNormals());
  for (std::size_t i = 0; i < back.size(); i += 97) {
    // float32 storage of values that were float32-representable decimal text in the source.
    EXPECT_NEAR((back.positions[i] - original.positions[i]).norm(), 0.0, 1e-4);
  }
}

TEST_F(CliTest, ConvertScalesMetresToMillimetres) {
  const std::string out = (dir_ / "bun0_mm.ply").string();
  CommandResult r = RunCli("cloud convert --scale 1000 " + Data("real/pcl/bun0.pcd") + " " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto metres = lasercell::io::ReadPointCloud(Data("real/pcl/bun0.pcd"));
  const auto mm = lasercell::io::ReadPointCloud(out);
  ASSERT_EQ(mm.size(), metres.size());
  EXPECT_NEAR(mm.Bounds().Diagonal(), 1000 * metres.Bounds().Diagonal(), 1e-2);
}

TEST_F(CliTest, MissingFileIsOneLineExitTwo) {
  const CommandResult r = RunCli("cloud info " + (dir_ / "nope.ply").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("nope.ply"));
}

TEST_F(CliTest, CorruptInputWritesNothing) {
  const fs::path bad = dir_ / "bad.ply";
  std::ofstream(bad) << "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n"
                        "property float y\nproperty float z\nend_header\n1 2 3\n";
  const fs::path out = dir_ / "out.pcd";
  const CommandResult r = RunCli("cloud convert " + bad.string() + " " + out.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("bad.ply"));
  EXPECT_FALSE(fs::exists(out));
  // No temporary files left behind either.
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr(".tmp-")));
  }
}

TEST_F(CliTest, ConvertRejectsUnknownOutputTypeAndBadScale) {
  CommandResult r =
      RunCli("cloud convert " + Data("real/pcl/bun4.pcd") + " " + (dir_ / "x.xyz").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("x.xyz"));
  r = RunCli("cloud convert --scale -3 " + Data("real/pcl/bun4.pcd") + " " +
             (dir_ / "x.ply").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--scale"));
}

TEST_F(CliTest, FramesShowAndGetOnExampleCell) {
  const std::string cell = Data("demo/cell.yaml");
  CommandResult r = RunCli("frames show " + cell);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("vision_flange"));
  EXPECT_THAT(r.out, HasSubstr("sensor"));
  EXPECT_THAT(r.out, HasSubstr("by: "));
  r = RunCli("frames get " + cell + " --to vision_flange --from sensor");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("vision_flange_from_sensor: {translation_mm: ["));
  EXPECT_THAT(r.out, HasSubstr("rotation_wxyz: ["));
  // Through the UR5's dynamic edge: all-zero joints.
  r = RunCli("frames get " + cell + " --to vision_base --from vision_flange --joints 0,0,0,0,0,0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // UR5 at zero joints: flange at (a2 + a3, -(d4 + d6), d1 - d5) mm.
  const auto at = r.out.find("translation_mm: [");
  ASSERT_NE(at, std::string::npos) << r.out;
  double x = 0, y = 0, z = 0;
  ASSERT_EQ(std::sscanf(r.out.c_str() + at, "translation_mm: [%lf, %lf, %lf", &x, &y, &z), 3);
  EXPECT_NEAR(x, -817.25, 1e-9);
  EXPECT_NEAR(y, -191.45, 1e-9);
  EXPECT_NEAR(z, -5.491, 1e-9);
}

TEST_F(CliTest, FramesGetErrors) {
  const std::string cell = Data("demo/cell.yaml");
  CommandResult r = RunCli("frames get " + cell + " --to nowhere --from sensor");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("nowhere"));
  r = RunCli("frames get " + cell + " --to vision_base --from sensor");  // joints needed
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("vision_robot"));
  r = RunCli("frames get " + cell + " --to vision_base --from sensor --joints 0,0,x");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--joints"));
}

TEST_F(CliTest, BadCellFileIsOneLineExitTwo) {
  const fs::path cell = dir_ / "cell.yaml";
  std::ofstream(cell) << "format: lasercell.cell\nversion: 99\nframes: []\nedges: []\n";
  const CommandResult r = RunCli("frames show " + cell.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("cell.yaml"));
  EXPECT_THAT(r.err, HasSubstr("version"));
}

TEST_F(CliTest, LocalizeFindsTheParasaurolophusInRs1) {
  const std::string out = (dir_ / "result.json").string();
  const CommandResult r =
      RunCli("localize --model " + Data("real/uwa/parasaurolophus_6700.bin.ply") + " --scene " +
             Data("real/uwa/rs1_normals.bin.ply") + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(Slurp(out));
  EXPECT_EQ(j["format"], "lasercell.localization");
  ASSERT_TRUE(j["found"].get<bool>());
  ASSERT_GE(j["candidates"].size(), 1u);
  const auto& best = j["candidates"][0];
  EXPECT_EQ(best["rank"], 1);
  // The pose in the file notation of every lasercell file; the 4x4 rides along.
  ASSERT_EQ(best["scene_from_model"]["translation_mm"].size(), 3u);
  ASSERT_EQ(best["scene_from_model"]["rotation_wxyz"].size(), 4u);
  double q2 = 0;
  for (const auto& c : best["scene_from_model"]["rotation_wxyz"])
    q2 += c.get<double>() * c.get<double>();
  EXPECT_NEAR(q2, 1.0, 1e-12);
  ASSERT_EQ(best["scene_from_model_matrix"].size(), 4u);  // rows of a 4x4 matrix
  ASSERT_EQ(best["scene_from_model_matrix"][3].size(), 4u);
  EXPECT_EQ(best["scene_from_model_matrix"][3], nlohmann::json({0.0, 0.0, 0.0, 1.0}));
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(best["scene_from_model_matrix"][k][3].get<double>(),
                best["scene_from_model"]["translation_mm"][k].get<double>(), 1e-9);
  }
  EXPECT_GT(best["support"].get<double>(), 0.5);
  EXPECT_LT(best["icp"]["rmse_mm"].get<double>(), 2.0);
  EXPECT_TRUE(j["timings_ms"].contains("matching"));
}

TEST_F(CliTest, LocalizeWithoutThePartIsFoundFalseExitZero) {
  // The milk carton scene (PCL, converted to mm) holds no parasaurolophus.
  const std::string scene = (dir_ / "milk_scene_mm.ply").string();
  ASSERT_EQ(RunCli("cloud convert --scale 1000 " +
                   Data("real/pcl/milk_cartoon_all_small_clorox.pcd") + " " + scene)
                .exit_code,
            0);
  const std::string out = (dir_ / "result.json").string();
  const CommandResult r =
      RunCli("localize --model " + Data("real/uwa/parasaurolophus_6700.bin.ply") + " --scene " +
             scene + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(Slurp(out));
  EXPECT_FALSE(j["found"].get<bool>());
  EXPECT_TRUE(j["candidates"].empty());
  EXPECT_FALSE(j["message"].get<std::string>().empty());
}

TEST_F(CliTest, LocalizeBadOptionsAreOneLineExitTwoAndWriteNothing) {
  const fs::path opts = dir_ / "opts.yaml";
  std::ofstream(opts) << "matching:\n  refrence_stride: 3\n";
  const std::string out = (dir_ / "result.json").string();
  const std::string base = "localize --model " + Data("real/uwa/parasaurolophus_6700.bin.ply") +
                           " --scene " + Data("real/uwa/rs1_normals.bin.ply") + " --out " + out;
  CommandResult r = RunCli(base + " --options " + opts.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("matching.refrence_stride"));
  std::ofstream(opts, std::ios::trunc) << "matching:\n  reference_stride: -1\n";
  r = RunCli(base + " --options " + opts.string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  std::ofstream(opts, std::ios::trunc) << "model: {angle_step_rad: -0.1}\n";
  r = RunCli(base + " --options " + opts.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("angle_step_rad"));
  r = RunCli(base + " --max-instances 0");
  EXPECT_EQ(r.exit_code, 2);
  r = RunCli(base + " --viewpoint 1,2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliTest, LocalizeSavesAndReusesAPrebuiltModel) {
  const std::string model = (dir_ / "para.ppfm").string();
  const std::string out1 = (dir_ / "r1.json").string(), out2 = (dir_ / "r2.json").string();
  const std::string scene = Data("real/uwa/rs1_normals.bin.ply");
  CommandResult r = RunCli("localize --quiet --threads 1 --model " +
                           Data("real/uwa/parasaurolophus_6700.bin.ply") + " --scene " + scene +
                           " --out " + out1 + " --save-model " + model);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.out.empty());
  r = RunCli("localize --quiet --threads 1 --model " + model + " --scene " + scene + " --out " +
             out2);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto a = nlohmann::json::parse(Slurp(out1)), b = nlohmann::json::parse(Slurp(out2));
  EXPECT_EQ(a["candidates"][0]["scene_from_model"], b["candidates"][0]["scene_from_model"]);
  EXPECT_EQ(a["candidates"][0]["scene_from_model_matrix"],
            b["candidates"][0]["scene_from_model_matrix"]);
}

// Simulation profile: ideal (`simulate seat` without --profile).
TEST_F(CliTest, SimulateSeatIsDeterministicAndReadable) {
  const fs::path a = dir_ / "a", b = dir_ / "b";
  CommandResult r = RunCli("simulate seat --quiet --placements 1 --seed 7 --out " + a.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunCli("simulate seat --quiet --placements 1 --seed 7 --threads 1 --out " + b.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(a)) {
    if (!entry.is_regular_file()) continue;
    ++files;
    const fs::path other = b / fs::relative(entry.path(), a);
    EXPECT_EQ(Slurp(entry.path()), Slurp(other)) << entry.path();
  }
  EXPECT_GE(files, 5);
  // The truth cell file is readable by the frames tools.
  r = RunCli("frames get " + (a / "truth/cell.yaml").string() +
             " --to handling_base --from seat_000");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("handling_base_from_seat_000"));
}

TEST_F(CliTest, SimulateBadConfigNamesTheField) {
  const fs::path cfg = dir_ / "sim.yaml";
  std::ofstream(cfg) << "seats: {count: -1}\n";
  CommandResult r =
      RunCli("simulate cell --out " + (dir_ / "out").string() + " --config " + cfg.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("seats.count"));
  std::ofstream(cfg, std::ios::trunc) << "sensor: {standof_mm: 700}\n";
  r = RunCli("simulate cell --out " + (dir_ / "out").string() + " --config " + cfg.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("standof_mm"));
}

// A named profile: an unknown name and a profile beside a config file are bad input (exit 2,
// nothing simulated); the realistic profile's truth names it.
TEST_F(CliTest, SimulateProfileIsNamedOnceAndRecorded) {
  const std::string out = (dir_ / "out").string();
  CommandResult r = RunCli("simulate seat --quiet --placements 1 --profile noisy --out " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("use ideal or realistic"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "truth"));
  const fs::path cfg = dir_ / "sim.yaml";
  std::ofstream(cfg) << "profile: realistic\n";
  r = RunCli("simulate seat --quiet --placements 1 --profile ideal --config " + cfg.string() +
             " --out " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("not both"));
  r = RunCli("simulate seat --quiet --placements 1 --profile realistic --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(Slurp(dir_ / "out" / "truth" / "sim_config.yaml"), HasSubstr("profile: realistic"));
}

// The accuracy benches take the realistic profile by default; a wrong name is bad input, said
// before any output.
TEST_F(CliTest, BenchesRefuseAnUnknownProfileBeforeRunning) {
  for (const std::string& cmd : std::vector<std::string>{
           "bench calibration --profile noisy",
           "bench table1 --placements 1 --profile noisy --work " + (dir_ / "t1").string()}) {
    const CommandResult r = RunCli(cmd);
    EXPECT_EQ(r.exit_code, 2) << cmd;
    EXPECT_THAT(r.err, HasSubstr("use ideal or realistic")) << cmd;
    EXPECT_EQ(r.out, "") << cmd;
  }
  EXPECT_FALSE(fs::exists(dir_ / "t1"));
}

TEST_F(CliTest, BenchRegistrationPrintsPoseErrorTable) {
  // OpenCV training takes about a minute: the full comparison runs by hand (BENCHMARKS.md).
  const std::string json = (dir_ / "bench.json").string();
  const CommandResult r =
      RunCli("bench registration --runs 2 --skip-opencv --skip-pcl --icp-starts 3 --json " + json);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("| lasercell |"));
  EXPECT_THAT(r.out, HasSubstr("pose error"));
  EXPECT_THAT(r.out, HasSubstr("RMS err mm"));
  EXPECT_THAT(r.out, HasSubstr("lasercell AlignIcp"));
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("OpenCV")));
  const auto j = nlohmann::json::parse(Slurp(json));
  ASSERT_GE(j["rows"].size(), 2u);
  EXPECT_EQ(j["rows"][1]["method"], "lasercell");
  EXPECT_EQ(j["rows"][1]["top_pose"], "<= 2 mm");
  EXPECT_LT(j["rows"][1]["pose_error"]["rms_mm"].get<double>(), 2.0);
}

TEST_F(CliTest, BenchRegistrationBadArgumentsExitTwo) {
  CommandResult r = RunCli("bench registration --runs 0 --skip-opencv --skip-pcl");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--runs"));
  r = RunCli("bench registration --runs 1 --skip-opencv --skip-pcl --model " +
             (dir_ / "missing.ply").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("missing.ply"));
  r = RunCli("bench");
  EXPECT_EQ(r.exit_code, 2);
}

}  // namespace
}  // namespace lasercell::test
