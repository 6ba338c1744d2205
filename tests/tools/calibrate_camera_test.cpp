// `lasercell calibrate camera` end to end on OpenCV's sample images
// (datasets/real/opencv_chessboard): outputs, re-read JSON, and the bad-input cases (unreadable
// image, wrong board size, too few views, no matching file).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/cli_util.hpp"

// In lasercell::test: the shared helpers of tests/cli_util.hpp (RunCli, Slurp, ...) by name.
namespace lasercell::test {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class CalibrateCameraCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = MakeTestDir("calcam");
    fs::create_directories(dir_ / "images");
  }
  void TearDown() override { RemoveTestDir(dir_); }

  static CommandResult Exec(const std::string& args) { return RunCli("calibrate camera " + args); }
  // Copies left<NN>.jpg into dir_/images.
  void CopyImages(std::initializer_list<int> numbers) const {
    for (int n : numbers) {
      char name[32];
      std::snprintf(name, sizeof(name), "left%02d.jpg", n);
      fs::copy_file(std::string(LASERCELL_SOURCE_DIR) + "/datasets/real/opencv_chessboard/" + name,
                    dir_ / "images" / name);
    }
  }
  std::string Images() const { return "--images '" + (dir_ / "images").string() + "/*.jpg'"; }
  std::string Outputs() const {
    return "--out " + (dir_ / "cam.cameramodel").string() + " --json " +
           (dir_ / "cam.json").string() + " --quiet";
  }

  fs::path dir_;
};

// OpenCV's sample result (left_intrinsics.yml): RMS 0.3926 px, fx = fy = 535.92 px with the
// 5-term model and a fixed aspect ratio.
TEST_F(CalibrateCameraCli, OpenCvSamplesMatchOpenCvsResultAndJsonReadsBack) {
  const std::string all = "--images '" + std::string(LASERCELL_SOURCE_DIR) +
                          "/datasets/real/opencv_chessboard/left*.jpg'";
  const CommandResult r =
      Exec(all + " --board chessboard:9x6:25 --model opencv5 --fix-aspect " + Outputs());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(Slurp(dir_ / "cam.json"));
  EXPECT_EQ(j["format"], "lasercell.camera_calibration");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["lensmodel"], "LENSMODEL_OPENCV5");
  EXPECT_EQ(j["images_used"], 13);
  EXPECT_EQ(j["images_rejected"], 0);
  EXPECT_LE(j["rms_px"].get<double>(), 0.3926 * 1.01);
  EXPECT_EQ(j["intrinsics"][0]["name"], "fx");
  // OpenCV's sample value, from another detector: within 1 % (calib_test checks the solver
  // against cv::calibrateCamera on identical corners).
  EXPECT_NEAR(j["intrinsics"][0]["value"].get<double>() / 535.92, 1.0, 0.01);
  EXPECT_GT(j["intrinsics"][0]["sigma"].get<double>(), 0.0);
  EXPECT_EQ(j["intrinsics"][0]["value"], j["intrinsics"][1]["value"]);  // fixed aspect
  EXPECT_TRUE(j["focal_length_observable"].get<bool>());
  for (const auto& image : j["images"]) {
    EXPECT_TRUE(image["used"].get<bool>());
    EXPECT_GT(image["rms_px"].get<double>(), 0.0);
  }
  EXPECT_EQ(j["projection_uncertainty"]["grid_px"].size(), 12u);
  const std::string model = Slurp(dir_ / "cam.cameramodel");
  EXPECT_THAT(model, HasSubstr("LENSMODEL_OPENCV5"));
}

// The report: a self-contained page that loads in headless chromium without script errors and
// holds the plots (2 residual histograms, residual vectors, per-image RMS, coverage,
// projection uncertainty).
TEST_F(CalibrateCameraCli, ReportLoadsInHeadlessChromiumWithItsPlots) {
  CopyImages({1, 3, 4, 5, 6, 7, 8});
  const fs::path html = dir_ / "cam.html";
  const CommandResult r =
      Exec(Images() + " --board chessboard:9x6:25 --report " + html.string() + " " + Outputs());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string page = Slurp(html);
  for (const char* plot :
       {"Residual norm of the inlier corners", "Residual vectors over the image",
        "RMS reprojection error per image", "Coverage of the image by the observed corners",
        "Projection uncertainty (1 sigma"}) {
    EXPECT_THAT(page, HasSubstr(plot));
  }
  const std::string dom = HeadlessChromiumDom(html.string());
  ASSERT_FALSE(dom.empty()) << "chromium did not run (scripts/install-deps installs it)";
  EXPECT_THAT(dom, HasSubstr("data-report-ready=\"1\""));
  EXPECT_THAT(dom, HasSubstr("data-plots=\"6\""));
  EXPECT_EQ(dom.find("data-report-errors"), std::string::npos);
}

TEST_F(CalibrateCameraCli, UnreadableImageIsRejectedWithItsReason) {
  CopyImages({1, 3, 4, 5, 6, 7});
  std::ofstream(dir_ / "images" / "left99.jpg") << "not a jpeg";
  const CommandResult r = Exec(Images() + " --board chessboard:9x6:25 " + Outputs());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(Slurp(dir_ / "cam.json"));
  EXPECT_EQ(j["images_used"], 6);
  EXPECT_EQ(j["images_rejected"], 1);
  const auto& bad = j["images"].back();
  EXPECT_THAT(bad["file"].get<std::string>(), HasSubstr("left99.jpg"));
  EXPECT_EQ(bad["detection"], "unreadable");
  EXPECT_FALSE(bad["used"].get<bool>());
  EXPECT_THAT(bad["rejection_reason"].get<std::string>(), HasSubstr("not a readable image"));
}

TEST_F(CalibrateCameraCli, WrongBoardSizeIsAnErrorNamingTheSuspectedSize) {
  CopyImages({1, 3, 4});
  const CommandResult r = Exec(Images() + " --board chessboard:9x7:25 " + Outputs());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("found in 0 of 3 images"));
  EXPECT_THAT(r.err, HasSubstr("wrong board size"));
  EXPECT_FALSE(fs::exists(dir_ / "cam.cameramodel"));
}

TEST_F(CalibrateCameraCli, TooFewViewsIsAnError) {
  CopyImages({1, 3});
  const CommandResult r = Exec(Images() + " --board chessboard:9x6:25 " + Outputs());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("found in 2 of 2 images, need at least 3"));
  EXPECT_FALSE(fs::exists(dir_ / "cam.cameramodel"));
}

TEST_F(CalibrateCameraCli, GlobMatchingNothingAndBadOptionsAreErrors) {
  CommandResult r = Exec(Images() + " --board chessboard:9x6:25 " + Outputs());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("matches no file"));
  CopyImages({1});
  r = Exec(Images() + " --board chessboard:9x6 " + Outputs());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("expected chessboard:COLSxROWS:SQUARE_MM"));
  r = Exec(Images() + " --board chessboard:9x6:25 --model fisheye " + Outputs());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--model 'fisheye'"));
}

}  // namespace
}  // namespace lasercell::test
