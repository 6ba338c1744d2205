// FitSphere: accuracy on sensor-like half spheres, calibrated covariance, outliers, partial caps,
// degenerate input, and the Ceres cost functor's derivatives.
#include "calib/sphere_fit.hpp"

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "calib/cost_functions/sphere_distance_cost.hpp"
#include "core/error.hpp"
#include "tests/calib/sphere_test_util.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell::calib {
namespace {

using testing::SampleCap;

TEST(SphereDistanceCost, DerivativesMatchNumericDifferences) {
  datasets::Rng rng(11);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d p{rng.Uniform(-40, 40), rng.Uniform(-40, 40), rng.Uniform(-40, 40)};
    std::unique_ptr<ceres::CostFunction> cost(SphereDistanceCost::Create(p));
    double center[3] = {rng.Uniform(-5, 5), rng.Uniform(-5, 5), rng.Uniform(-5, 5)};
    double radius = rng.Uniform(10, 30);
    const double* params[2] = {center, &radius};
    ceres::NumericDiffOptions numeric;
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker checker(cost.get(), no_manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
    // And the value itself: |p - c| - R.
    EXPECT_NEAR(results.residuals[0],
                (p - Eigen::Vector3d(center[0], center[1], center[2])).norm() - radius, 1e-12);
  }
}

// Target: centre error <= 0.02 mm for a half sphere of r = 25 mm with sigma = 0.05 mm point
// noise, sampled like the simulated sensor (2.58 mm x 0.54 mm grid, up to 85 deg from the top:
// ~1400 points). Expected centre sigma ~0.003 mm, so 0.02 mm is > 5 sigma: 20 draws must all pass.
TEST(FitSphere, HalfSphereCentreWithinTwentyMicrometres) {
  datasets::Rng rng(2026);
  double worst_fixed = 0, worst_free = 0;
  for (int draw = 0; draw < 20; ++draw) {
    const Eigen::Vector3d c{rng.Uniform(-300, 300), rng.Uniform(-300, 300), rng.Uniform(500, 700)};
    const auto points = SampleCap(c, 25.0, 85.0, 0.05, rng);
    ASSERT_GT(points.size(), 1200u);
    SphereFitOptions fixed;
    fixed.radius_mm = 25.0;
    const SphereFitResult a = FitSphere(points, fixed);
    const SphereFitResult b = FitSphere(points);
    ASSERT_TRUE(a.success) << a.failure;
    ASSERT_TRUE(b.success) << b.failure;
    EXPECT_TRUE(a.converged && b.converged);
    worst_fixed = std::max(worst_fixed, (a.center - c).norm());
    worst_free = std::max(worst_free, (b.center - c).norm());
    EXPECT_NEAR(b.radius_mm, 25.0, 5 * b.radius_sigma_mm);
    EXPECT_NEAR(a.residual_sigma_mm, 0.05, 0.005);  // normal component of the iso noise
    EXPECT_TRUE(b.radius_determined);
  }
  EXPECT_LE(worst_fixed, 0.02);
  EXPECT_LE(worst_free, 0.02);
  std::printf(
      "[ measured ] half sphere r=25, sigma 0.05: worst centre error over 20 draws "
      "%.4f mm (radius given), %.4f mm (free)\n",
      worst_fixed, worst_free);
}

// Calibrated uncertainty: truth within the reported 1-sigma 60-76 % of the time (per
// coordinate, 150 draws x 3 coordinates), for the radius given and free.
TEST(FitSphere, CentreCovarianceIsCalibrated) {
  for (bool free_radius : {false, true}) {
    datasets::Rng rng(free_radius ? 77 : 78);
    int inside = 0, total = 0;
    for (int draw = 0; draw < lasercell::test::Draws(150); ++draw) {
      const Eigen::Vector3d c{rng.Uniform(-50, 50), rng.Uniform(-50, 50), rng.Uniform(-50, 50)};
      const auto points = SampleCap(c, 25.0, 80.0, 0.05, rng, 2.58, 1.5);
      SphereFitOptions options;
      if (!free_radius) options.radius_mm = 25.0;
      const SphereFitResult r = FitSphere(points, options);
      ASSERT_TRUE(r.success);
      const Eigen::Matrix3d cov = r.CenterCovariance();
      for (int k = 0; k < 3; ++k) {
        inside += std::abs(r.center[k] - c[k]) <= std::sqrt(cov(k, k));
        ++total;
      }
    }
    const double fraction = static_cast<double>(inside) / total;
    std::printf("[ measured ] sphere centre 1-sigma coverage (%s radius): %.3f over %d\n",
                free_radius ? "free" : "given", fraction, total);
    if (!lasercell::test::StatisticsAsserted()) continue;
    EXPECT_GE(fraction, 0.60);
    EXPECT_LE(fraction, 0.76);
  }
}

TEST(FitSphere, GrossOutliersAreFlaggedAndDoNotPull) {
  datasets::Rng rng(5);
  const Eigen::Vector3d c(10, -20, 600);
  auto points = SampleCap(c, 25.0, 85.0, 0.05, rng);
  const std::size_t clean = points.size();
  // 10 % outliers: a stray surface 1-10 mm off the sphere (reflections, stand edge, dust).
  for (std::size_t i = 0; i < clean / 10; ++i) {
    const Eigen::Vector3d dir =
        Eigen::Vector3d{rng.Normal(), rng.Normal(), std::abs(rng.Normal())}.normalized();
    points.push_back(c + (25.0 + rng.Uniform(1.0, 10.0)) * dir);
  }
  SphereFitOptions options;
  options.radius_mm = 25.0;
  const SphereFitResult r = FitSphere(points, options);
  ASSERT_TRUE(r.success);
  EXPECT_LE((r.center - c).norm(), 0.02);
  std::size_t flagged_outliers = 0;
  for (std::size_t i = clean; i < points.size(); ++i) flagged_outliers += r.outlier[i];
  EXPECT_EQ(flagged_outliers, points.size() - clean);
  // Inliers flagged: at 4 robust sigmas, well under 1 %.
  std::size_t flagged_inliers = 0;
  for (std::size_t i = 0; i < clean; ++i) flagged_inliers += r.outlier[i];
  EXPECT_LT(flagged_inliers, clean / 100);
  EXPECT_EQ(r.num_outliers, flagged_outliers + flagged_inliers);
}

TEST(FitSphere, SmallCapWithFreeRadiusSaysTheRadiusIsNotFixed) {
  datasets::Rng rng(9);
  const Eigen::Vector3d c(0, 0, 0);
  const auto points = SampleCap(c, 25.0, 12.0, 0.05, rng, 0.5, 0.5);
  const SphereFitResult free_fit = FitSphere(points);
  ASSERT_TRUE(free_fit.success);
  EXPECT_FALSE(free_fit.radius_determined);
  ASSERT_FALSE(free_fit.warnings.empty());
  EXPECT_NE(free_fit.warnings[0].find("too small to fix the radius"), std::string::npos)
      << free_fit.warnings[0];
  EXPECT_NE(free_fit.Summary().find("radius not determined"), std::string::npos);
  // With the radius given, the same cap fixes the centre (within 4 reported sigmas).
  SphereFitOptions given;
  given.radius_mm = 25.0;
  const SphereFitResult fixed = FitSphere(points, given);
  ASSERT_TRUE(fixed.success);
  EXPECT_TRUE(fixed.radius_determined);
  const Eigen::Vector3d err = fixed.center - c;
  EXPECT_LE(std::sqrt(err.dot(fixed.CenterCovariance().inverse() * err)), 4.0);
}

// Points that cannot determine a sphere are degenerate input (the error rule): InputError
// naming the degeneracy. They were reported in the result before.
TEST(FitSphere, TooFewOrCoplanarPointsAreAnInputErrorNamingTheDegeneracy) {
  const std::vector<Eigen::Vector3d> three = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  try {
    FitSphere(three);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 5 with a free radius"), std::string::npos)
        << e.what();
  }
  SphereFitOptions given;
  given.radius_mm = 10.0;
  try {
    FitSphere(three, given);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 4 with the radius known"), std::string::npos)
        << e.what();
  }
  std::vector<Eigen::Vector3d> plane;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) plane.emplace_back(i, j, 3.0);
  }
  try {
    FitSphere(plane);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lie on a plane"), std::string::npos) << e.what();
  }
  // With the radius known a plane patch has a sphere (either side): fitted, not thrown.
  EXPECT_NO_THROW(FitSphere(plane, given));
}

TEST(FitSphere, AFailedFitSaysSoInItsSummary) {
  SphereFitResult failed;
  failed.failure = "only 2 of 9 points agree with one sphere";
  EXPECT_NE(failed.Summary().find("sphere fit failed"), std::string::npos);
}

TEST(FitSphere, BadOptionsAndPointsThrowNamingTheField) {
  SphereFitOptions o;
  o.radius_mm = -1;
  try {
    FitSphere(std::vector<Eigen::Vector3d>(10, Eigen::Vector3d::Zero()), o);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("SphereFitOptions.radius_mm"), std::string::npos);
  }
  std::vector<Eigen::Vector3d> bad(10, Eigen::Vector3d(1, 2, 3));
  bad[4].x() = std::nan("");
  try {
    FitSphere(bad);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 4 is not finite"), std::string::npos);
  }
}

}  // namespace
}  // namespace lasercell::calib
