#include "calib/camera_model.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "calib/camera_uncertainty.hpp"
#include "core/error.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::calib {
namespace {

CameraModel Opencv8() {
  return CameraModel(
      "LENSMODEL_OPENCV8",
      {1132.0, 1131.5, 515.3, 508.6, -0.112, 0.071, 2.1e-4, -1.3e-4, -0.018, 0.011, -0.006, 0.002},
      1024, 1024);
}

// ---- The intrinsics covariance: kept by the model, stored in its file (which mrcal still
// reads), checked on input; its first-order propagation (calib/camera_uncertainty.hpp) against
// the analytic J Sigma J^T.

/// A full-rank, correlated covariance of the 12 intrinsics: sigmas 0.15 px for fx fy cx cy,
/// 1e-3 .. 1e-5 for the distortion, correlation 0.5^|i-j|.
Eigen::MatrixXd Covariance() {
  const double sigma[12] = {0.15, 0.15, 0.12, 0.12, 1e-3, 2e-3, 1e-5, 1e-5, 3e-3, 2e-3, 3e-3, 2e-3};
  Eigen::MatrixXd c(12, 12);
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 12; ++j) c(i, j) = sigma[i] * sigma[j] * std::pow(0.5, std::abs(i - j));
  }
  return c;
}

TEST(CameraUncertainty, TheCovarianceRoundTripsThroughTheFileAndMrcalStillReadsIt) {
  CameraModel model = Opencv8();
  model.SetIntrinsicsCovariance(Covariance());
  const test::TestDir dir("camera_covariance");
  const std::string path = dir.File("model.cameramodel");
  SaveCameraModel(path, model, "with covariance");
  const CameraModel back = LoadCameraModel(path);
  EXPECT_EQ(back.intrinsics(), model.intrinsics());
  ASSERT_EQ(back.intrinsics_covariance().rows(), 12);
  EXPECT_TRUE(back.intrinsics_covariance() == model.intrinsics_covariance());
  // mrcal's Python reader ignores the extra key and reads the same model.
  const test::CommandResult python = test::RunCommand(
      "/usr/bin/python3 -c \"import sys, mrcal; m = mrcal.cameramodel(sys.argv[1]); "
      "print(m.intrinsics()[0], m.intrinsics()[1][0])\" " +
      path + " 2>&1");
  ASSERT_EQ(python.exit_code, 0) << python.out;
  EXPECT_NE(python.out.find("LENSMODEL_OPENCV8 1132.0"), std::string::npos) << python.out;
  // A model without the key has no covariance.
  const CameraModel plain = ParseCameraModel(CameraModelText(Opencv8()), "plain");
  EXPECT_EQ(plain.intrinsics_covariance().size(), 0);
  EXPECT_EQ(CameraModelText(Opencv8()).find("lasercell_intrinsics_covariance"), std::string::npos);
}

TEST(CameraUncertainty, ABadCovarianceIsRefusedNamingWhatIsWrong) {
  CameraModel model = Opencv8();
  const auto message = [&](const Eigen::MatrixXd& c) {
    try {
      model.SetIntrinsicsCovariance(c);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message(Eigen::MatrixXd::Identity(4, 4)).find("must be 12 x 12, got 4 x 4"),
            std::string::npos);
  Eigen::MatrixXd c = Covariance();
  c(0, 1) += 1e-3;
  EXPECT_NE(message(c).find("not symmetric"), std::string::npos);
  c = Covariance();
  c(2, 2) = -1e-4;
  EXPECT_NE(message(c).find("negative variance"), std::string::npos);
  c = Covariance();
  c(3, 3) = std::nan("");
  EXPECT_NE(message(c).find("not finite"), std::string::npos);
  // In a file: the wrong count, and a value that is not a number, are file errors naming the key.
  model.SetIntrinsicsCovariance(Covariance());
  std::string text = CameraModelText(model);
  const std::size_t last = text.rfind(',');
  std::string short_text = text;
  short_text.erase(last, text.find(']', last) - last);  // drops the last number
  try {
    ParseCameraModel(short_text, "short.cameramodel");
    FAIL() << "accepted 143 numbers";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("short.cameramodel"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("must hold 144 finite numbers"), std::string::npos)
        << e.what();
  }
  std::string word = text;
  word.replace(word.find("'lasercell_intrinsics_covariance': [") + 37, 0, "x");
  EXPECT_THROW(ParseCameraModel(word, "word.cameramodel"), FileError);
}

TEST(CameraUncertainty, PropagationEqualsTheJacobianSandwich) {
  CameraModel model = Opencv8();
  model.SetIntrinsicsCovariance(Covariance());
  // f: the pixels of three points (nonlinear in the distortion terms).
  const Eigen::Vector3d points[3] = {
      {120.0, -80.0, 650.0}, {-300.0, 250.0, 700.0}, {10.0, 5.0, 400.0}};
  const auto pixels = [&](const CameraModel& c) {
    Eigen::VectorXd q(6);
    for (int k = 0; k < 3; ++k) q.segment<2>(2 * k) = c.Project(points[k]);
    return q;
  };
  const Eigen::MatrixXd propagated = PropagateIntrinsicsCovariance(model, pixels);
  Eigen::MatrixXd j(6, 12);
  for (int k = 0; k < 3; ++k) {
    Eigen::Matrix<double, 2, Eigen::Dynamic> dq_di;
    model.Project(points[k], nullptr, &dq_di);
    j.middleRows<2>(2 * k) = dq_di;
  }
  const Eigen::MatrixXd analytic = j * model.intrinsics_covariance() * j.transpose();
  EXPECT_LT((propagated - analytic).cwiseAbs().maxCoeff(), 1e-6 * analytic.cwiseAbs().maxCoeff())
      << "propagated\n"
      << propagated << "\nanalytic\n"
      << analytic;
  // Axis by axis: the steps span the covariance (sum of s_k s_k^T) and each response is the
  // Jacobian times its step, so the columns are what a consumer can propagate mode by mode.
  const IntrinsicsAxes axes = PropagateIntrinsicsAxes(model, pixels);
  const Eigen::MatrixXd spanned = axes.intrinsics_steps * axes.intrinsics_steps.transpose();
  EXPECT_LT((spanned - model.intrinsics_covariance()).cwiseAbs().maxCoeff(),
            1e-9 * model.intrinsics_covariance().cwiseAbs().maxCoeff());
  const Eigen::MatrixXd linear = j * axes.intrinsics_steps;
  EXPECT_LT((axes.responses - linear).cwiseAbs().maxCoeff(), 1e-3 * linear.cwiseAbs().maxCoeff());
  // Without a stored covariance there is nothing to propagate, and it says so.
  EXPECT_NE(CameraPropagationProblem(Opencv8()).find("no intrinsics covariance"),
            std::string::npos);
  EXPECT_THROW(PropagateIntrinsicsCovariance(Opencv8(), pixels), InputError);
}

TEST(CameraModel, ProjectUnprojectRoundTrip) {
  const CameraModel model = Opencv8();
  for (double u : {0.0, 200.5, 511.0, 1023.0}) {
    for (double v : {0.0, 333.3, 1023.0}) {
      const Eigen::Vector3d ray = model.Unproject({u, v});
      EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
      const Eigen::Vector2d q = model.Project(700.0 * ray);
      EXPECT_NEAR(q.x(), u, 1e-6);
      EXPECT_NEAR(q.y(), v, 1e-6);
    }
  }
}

TEST(CameraModel, GradientsMatchNumericDifferences) {
  const CameraModel model = Opencv8();
  const Eigen::Vector3d p(120.0, -80.0, 650.0);
  Eigen::Matrix<double, 2, 3> dq_dp;
  Eigen::Matrix<double, 2, Eigen::Dynamic> dq_di;
  model.Project(p, &dq_dp, &dq_di);
  ASSERT_EQ(dq_di.cols(), 12);
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[k] = 1e-4;
    const Eigen::Vector2d num = (model.Project(p + d) - model.Project(p - d)) / 2e-4;
    EXPECT_NEAR((num - dq_dp.col(k)).norm(), 0.0, 1e-6);
  }
  for (int k = 0; k < 12; ++k) {
    std::vector<double> a = model.intrinsics(), b = model.intrinsics();
    const double h = 1e-6 * std::max(1.0, std::abs(a[k]));
    a[k] += h;
    b[k] -= h;
    const Eigen::Vector2d num = (model.ProjectWithIntrinsics(a.data(), p, nullptr, nullptr) -
                                 model.ProjectWithIntrinsics(b.data(), p, nullptr, nullptr)) /
                                (2 * h);
    EXPECT_NEAR((num - dq_di.col(k)).norm(), 0.0, 1e-4 * std::max(1.0, num.norm())) << k;
  }
}

TEST(CameraModel, FileRoundTripIsExact) {
  const CameraModel model = Opencv8();
  const test::TestDir dir("camera_model");
  const std::string path = dir.File("model.cameramodel");
  SaveCameraModel(path, model, "test model\nsecond line");
  const CameraModel back = LoadCameraModel(path);
  EXPECT_EQ(back.lensmodel(), model.lensmodel());
  EXPECT_EQ(back.intrinsics(), model.intrinsics());
  EXPECT_EQ(back.width_px(), 1024);
  EXPECT_EQ(back.height_px(), 1024);
}

TEST(CameraModel, SplinedModelNameRoundTrips) {
  const std::string name = "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=8_Ny=6_fov_x_deg=60";
  // 4 core + 2 * Nx * Ny control points.
  std::vector<double> intrinsics(4 + 2 * 8 * 6, 0.0);
  intrinsics[0] = intrinsics[1] = 900.0;
  intrinsics[2] = 319.5;
  intrinsics[3] = 239.5;
  const CameraModel model(name, intrinsics, 640, 480);
  const CameraModel back = ParseCameraModel(CameraModelText(model), "mem");
  EXPECT_EQ(back.lensmodel(), name);
  EXPECT_EQ(back.intrinsics(), intrinsics);
}

// mrcal's own Python tools (Debian python3-mrcal, pulled in by the `mrcal` package that
// scripts/install-deps installs) read the files we write: same lens model, bit-identical
// intrinsics, and mrcal.project agrees with our projection.
TEST(CameraModel, MrcalsOwnToolsReadOurFiles) {
  const CameraModel model = Opencv8();
  const test::TestDir dir("mrcal_tools");
  const std::string path = dir.File("model.cameramodel");
  SaveCameraModel(path, model, "written by lasercell's camera_model_test");
  const std::string script =
      "import sys, numpy as np, mrcal\n"
      "m = mrcal.cameramodel(sys.argv[1])\n"
      "lens, intr = m.intrinsics()\n"
      "q = mrcal.project(np.array([120.0, -80.0, 650.0]), lens, intr)\n"
      "print(lens, m.imagersize()[0], m.imagersize()[1])\n"
      "print(' '.join(float(x).hex() for x in intr))\n"
      "print(repr(float(q[0])), repr(float(q[1])))\n";
  const std::string script_path = dir.File("read_model.py");
  test::Spit(script_path, script);
  const test::CommandResult python =
      test::RunCommand("/usr/bin/python3 " + script_path + " " + path + " 2>&1");
  const std::string& out = python.out;
  ASSERT_EQ(python.exit_code, 0) << out;
  std::istringstream lines(out);
  std::string lens;
  int width = 0, height = 0;
  lines >> lens >> width >> height;
  ASSERT_EQ(lens, "LENSMODEL_OPENCV8") << out;
  EXPECT_EQ(width, 1024);
  EXPECT_EQ(height, 1024);
  for (double expected : model.intrinsics()) {
    std::string hex;
    lines >> hex;
    EXPECT_EQ(std::strtod(hex.c_str(), nullptr), expected) << hex;
  }
  double u = 0, v = 0;
  lines >> u >> v;
  const Eigen::Vector2d q = model.Project(Eigen::Vector3d(120.0, -80.0, 650.0));
  EXPECT_NEAR(u, q.x(), 1e-9);
  EXPECT_NEAR(v, q.y(), 1e-9);
}

TEST(CameraModel, BadInputsSayWhatIsWrong) {
  EXPECT_THROW(CameraModel("LENSMODEL_NOPE", {1, 2, 3, 4}, 10, 10), InputError);
  try {
    CameraModel("LENSMODEL_OPENCV8", {1, 2, 3, 4}, 10, 10);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("needs 12 intrinsics, got 4"), std::string::npos);
  }
  EXPECT_THROW(CameraModel("LENSMODEL_PINHOLE", {1, 1, 1, 1}, 0, 10), InputError);
  EXPECT_THROW(ParseCameraModel("{ 'nope': 1 }", "bad.cameramodel"), FileError);
  EXPECT_THROW(LoadCameraModel("/nonexistent/x.cameramodel"), FileError);
}

// A lens whose distortion turns back inside the imager has pixels without a ray (or with a ray
// that projects elsewhere): r_d = r (1 + k1 r^2) peaks at r = 1 / sqrt(-3 k1), here r = 0.82,
// while the imager's corners sit at r = 1.03 (fx 700 px, 1024 px square).
TEST(CameraModel, LensInversionProblemFindsALensThatFoldsOverInsideTheImager) {
  EXPECT_EQ(LensInversionProblem(Opencv8()), "");
  const CameraModel mild("LENSMODEL_OPENCV4", {700, 700, 511.5, 511.5, -0.1, 0, 0, 0}, 1024, 1024);
  EXPECT_EQ(LensInversionProblem(mild), "");
  const CameraModel folded("LENSMODEL_OPENCV4", {700, 700, 511.5, 511.5, -0.5, 0, 0, 0}, 1024,
                           1024);
  const std::string problem = LensInversionProblem(folded);
  EXPECT_NE(problem.find("the lens model folds over there"), std::string::npos) << problem;
  // Inside the central 300 px the folded lens still inverts; the check covers a region.
  EXPECT_TRUE(CheckLensInversion(
                  folded, Eigen::AlignedBox2d(Eigen::Vector2d(362, 362), Eigen::Vector2d(662, 662)))
                  .ok());
  const LensInversionCheck whole = CheckLensInversion(folded);
  // No ray beyond r_d = 0.544 (381 px): 1 - pi 381^2 / 1024^2 = 57 % of the imager.
  EXPECT_NEAR(whole.FractionWithoutRay(), 0.57, 0.05);
  // The same lens on a smaller imager (corner radius 0.51 < 0.82) is fine.
  const CameraModel cropped("LENSMODEL_OPENCV4", {700, 700, 255.5, 255.5, -0.5, 0, 0, 0}, 512, 512);
  EXPECT_EQ(LensInversionProblem(cropped), "");
  EXPECT_THROW(LensInversionProblem(mild, 1), InputError);
  EXPECT_THROW(LensInversionProblem(mild, 33, 0.0), InputError);
}

// mrcal's lexer reads past the end of a buffer that stops inside a comment or a quoted string (a
// truncated file crashed `scan triangulate` with SIGSEGV). Every prefix of a valid model, and
// seeded random edits of it, must either parse or throw a FileError naming the file.
TEST(CameraModel, TruncatedOrMangledTextIsAFileErrorNotACrash) {
  const std::string text = CameraModelText(Opencv8(), "a comment line");
  const auto parse_or_file_error = [](const std::string& t) {
    try {
      ParseCameraModel(t, "cut.cameramodel");
      return true;
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("cut.cameramodel"), std::string::npos) << e.what();
      return false;
    }
  };
  // A prefix is complete once it holds the final '}'; every shorter one is an error.
  const std::size_t complete = text.rfind('}') + 1;
  for (std::size_t n = 0; n <= text.size(); ++n) {
    EXPECT_EQ(parse_or_file_error(text.substr(0, n)), n >= complete) << "prefix of " << n;
  }

  std::mt19937 rng(7);
  const std::string inserts = "{}[]()'\",#\n0.e-";
  for (int k = 0; k < 2000; ++k) {
    std::string t = text;
    for (int e = 0; e < 3; ++e) {
      const std::size_t pos = rng() % t.size();
      switch (rng() % 3) {
        case 0:
          t[pos] = static_cast<char>(rng() % 256);
          break;
        case 1:
          t.insert(pos, 1, inserts[rng() % inserts.size()]);
          break;
        default:
          t.resize(std::max<std::size_t>(pos, 1));
          break;
      }
    }
    parse_or_file_error(t);
  }
  try {
    ParseCameraModel("# lasercell-cameramodel v1\n{\n  'lensmodel':  'LENSMODEL_OPE",
                     "cut.cameramodel");
    FAIL();
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3: a quoted string is not closed"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lasercell::calib

// An OPENCV8 fit of a simulated cell (seed 103) whose fold is a sliver at the bottom of the
// imager: a 33 x 33 grid (32 px steps) stepped over it and the triangulator then refused the
// camera; the default grid (8 px steps) finds it.
namespace lasercell::calib {
TEST(CameraModel, LensInversionCheckFindsANarrowFold) {
  const CameraModel m(
      "LENSMODEL_OPENCV8",
      {1131.9808287438336, 1131.9805639738659, 515.3141447602065, 508.58591037210203,
       -8.243658142967805, 14.558034061666534, 0.00022565673964037192, -0.00014926363647190332,
       10.242592125125572, -8.12071436120108, 13.478289513137199, 12.610510814922677},
      1024, 1024);
  // The analytic radial check finds the ring at any grid density; the 129-grid finds it too.
  EXPECT_FALSE(CheckLensInversion(m, {}, 33).ok());
  EXPECT_GT(CheckLensInversion(m, {}, 33).radial_fold_px, 0.0);
  const LensInversionCheck check = CheckLensInversion(m);
  EXPECT_FALSE(check.ok());
  EXPECT_GT(check.reversed_cells, 0) << check.Describe();
  EXPECT_NE(LensInversionProblem(m), "");
}

// A ray that points sideways or backwards is no ray for a triangulator that looks ahead, even
// when it projects back exactly. A stereographic lens (r = 2 f tan(theta / 2)) with f = 100 px
// on a 1000 px imager sees theta = 2 atan(499.5 / 200) = 136 deg at its edge midpoints: the
// outer ring of pixels (beyond theta = 90 deg, r = 200 px) has rays with z <= 0, the centre
// has none.
TEST(CameraModel, LensInversionCheckRefusesRaysThatPointBackwards) {
  const CameraModel m("LENSMODEL_STEREOGRAPHIC", {100.0, 100.0, 499.5, 499.5}, 1000, 1000);
  const Eigen::Vector3d edge = m.Unproject({0.0, 499.5});
  ASSERT_LT(edge.z(), 0.0) << "the test's lens should see behind itself at the edge";
  const LensInversionCheck whole = CheckLensInversion(m, {}, 33);
  EXPECT_FALSE(whole.ok());
  EXPECT_GT(whole.without_ray, 0) << whole.Describe();
  EXPECT_LT(whole.without_ray, whole.pixels) << whole.Describe();
  EXPECT_NE(whole.Describe().find("no ray"), std::string::npos) << whole.Describe();
  // Within 150 px of the centre (theta <= 74 deg) every ray looks ahead.
  const LensInversionCheck centre = CheckLensInversion(
      m, Eigen::AlignedBox2d(Eigen::Vector2d(400, 400), Eigen::Vector2d(600, 600)), 33);
  EXPECT_TRUE(centre.ok()) << centre.Describe();
}

// Where a calibration's corners were is their convex hull, not their bounding box: the same
// stereographic lens, corners on a triangle inscribed in the 200 px disc of forward rays. The
// triangle's bounding box reaches beyond the disc at its empty corners (no board was there);
// the hull does not. A corner beyond the disc brings the backward rays inside.
TEST(CameraModel, LensInversionWithinTheObservedCornersIgnoresTheirBoxsEmptyCorners) {
  const CameraModel m("LENSMODEL_STEREOGRAPHIC", {100.0, 100.0, 499.5, 499.5}, 1000, 1000);
  const Eigen::Vector2d c(499.5, 499.5);
  std::vector<Eigen::Vector2d> corners;
  Eigen::AlignedBox2d box;
  for (const double deg : {90.0, 210.0, 330.0}) {
    const double a = deg * M_PI / 180.0;
    corners.push_back(c + 190.0 * Eigen::Vector2d(std::cos(a), std::sin(a)));
    box.extend(corners.back());
  }
  EXPECT_FALSE(CheckLensInversion(m, box, 33).ok());
  const LensInversionCheck hull = CheckLensInversionWithin(m, corners, 33);
  EXPECT_TRUE(hull.ok()) << hull.Describe();
  EXPECT_GT(hull.pixels, 33 * 33 / 3);
  EXPECT_LT(hull.pixels, 33 * 33);
  EXPECT_GT(hull.cells, 0);
  corners.push_back(c + Eigen::Vector2d(0.0, -430.0));
  const LensInversionCheck wider = CheckLensInversionWithin(m, corners, 33);
  EXPECT_FALSE(wider.ok());
  EXPECT_GT(wider.without_ray, 0) << wider.Describe();
  // Fewer than three corners span nothing.
  EXPECT_EQ(CheckLensInversionWithin(m, {c, c + Eigen::Vector2d(400.0, 0.0)}).pixels, 0);
}
}  // namespace lasercell::calib

namespace lasercell::calib {
namespace {

// An OPENCV8 fit to 20 noisy simulated views (the realistic profile, 0.036 px RMS) whose
// rational terms cancel where the boards were: its denominator 1 + k4 r^2 + k5 r^4 + k6 r^6
// nearly vanishes at r ~ 0.44 (~500 px from the centre) and the triangulator found a pixel
// (136, 191.5) without a ray, while a 129 x 129 grid (8 px apart) stepped over the ring. The
// analytic radial check finds it; the true lens (distortion of the simulator) passes.
TEST(CameraModel, LensInversionCheckFindsARingTheGridStepsOver) {
  const CameraModel folded(
      "LENSMODEL_OPENCV8",
      {1132.0970710387446, 1132.0851646200986, 515.2884585652554, 508.6076744009299,
       -8.981737731407616, 16.858031884907195, 0.00019252115995663932, -0.00012631204672982672,
       14.384427896860792, -8.856995089338458, 15.659248063421842, 17.240525707160465},
      1024, 1024);
  const LensInversionCheck check = CheckLensInversion(folded);
  EXPECT_FALSE(check.ok());
  EXPECT_GT(check.radial_fold_px, 300.0) << check.Describe();
  EXPECT_LT(check.radial_fold_px, 700.0) << check.Describe();
  EXPECT_NE(check.Describe().find("radial distortion turns back"), std::string::npos);
  // Within 200 px of the principal point the model is fine.
  const LensInversionCheck centre = CheckLensInversion(
      folded, Eigen::AlignedBox2d(Eigen::Vector2d(400, 400), Eigen::Vector2d(600, 600)));
  EXPECT_TRUE(centre.ok()) << centre.Describe();
  const CameraModel truth(
      "LENSMODEL_OPENCV8",
      {1132, 1132, 515.3, 508.6, -0.112, 0.071, 2.1e-4, -1.3e-4, -0.018, 0.011, -0.006, 0.002},
      1024, 1024);
  EXPECT_TRUE(CheckLensInversion(truth).ok()) << CheckLensInversion(truth).Describe();
}

}  // namespace
}  // namespace lasercell::calib
