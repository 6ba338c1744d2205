// FitRigidTransform: exactness, weighting, calibrated covariance, degenerate input.
#include "calib/rigid_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "datasets/rng.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell::calib {
namespace {

Eigen::Isometry3d RandomPose(datasets::Rng& rng) {
  const Eigen::Vector3d w{rng.Normal(), rng.Normal(), rng.Normal()};
  const Eigen::Vector3d t{rng.Uniform(-1000, 1000), rng.Uniform(-1000, 1000),
                          rng.Uniform(-1000, 1000)};
  return PoseFromRotationVector(w, t);
}

std::vector<Eigen::Vector3d> Layout() {
  // The simulated cell's four sphere centres (cell frame, mm).
  return {{-250, -140, 209}, {230, -160, 249}, {260, 150, 289}, {-220, 170, 329}};
}

TEST(FitRigidTransform, RecoversAnExactTransform) {
  datasets::Rng rng(3);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Isometry3d truth = RandomPose(rng);
    std::vector<Eigen::Vector3d> src = Layout(), dst;
    for (const auto& p : src) dst.push_back(truth * p);
    const RigidFitResult r = FitRigidTransform(src, dst);
    EXPECT_TRUE(r.converged);
    EXPECT_LT(RotationDistance(r.target_from_source, truth), 1e-12);
    EXPECT_LT(TranslationDistance(r.target_from_source, truth), 1e-9);
    EXPECT_LT(r.rms_mm, 1e-9);
    EXPECT_EQ(r.dof, 6);
  }
}

// A point with a large stated covariance must not pull the fit: the weighted estimate stays
// near the truth while the unweighted closed form does not.
TEST(FitRigidTransform, CovariancesWeightThePoints) {
  datasets::Rng rng(4);
  const Eigen::Isometry3d truth = RandomPose(rng);
  std::vector<Eigen::Vector3d> src = Layout(), dst;
  src.push_back({0, 0, 150});
  for (const auto& p : src) dst.push_back(truth * p);
  dst.back() += Eigen::Vector3d(3, -2, 4);  // off by 5 mm, and stated as sigma = 5 mm
  std::vector<Eigen::Matrix3d> dst_cov(src.size(), 1e-4 * Eigen::Matrix3d::Identity());
  dst_cov.back() = 25 * Eigen::Matrix3d::Identity();
  const std::vector<Eigen::Matrix3d> src_cov(src.size(), 1e-4 * Eigen::Matrix3d::Identity());
  const RigidFitResult weighted = FitRigidTransform(src, dst, src_cov, dst_cov);
  const Eigen::Isometry3d unweighted = HornRigidTransform(src, dst);
  EXPECT_LT(TranslationDistance(weighted.target_from_source, truth), 0.01);
  EXPECT_GT(TranslationDistance(unweighted, truth), 0.5);
  EXPECT_GT(weighted.residual_norms_mm.back(), 4.9);  // the bad point keeps its residual
}

// Calibrated uncertainty: 200 draws, anisotropic source and target noise as stated; truth inside
// the reported 1-sigma 60-76 % of the time over the 6 coordinates of the left perturbation.
TEST(FitRigidTransform, CovarianceIsCalibrated) {
  datasets::Rng rng(12);
  int inside = 0, total = 0;
  for (int draw = 0; draw < lasercell::test::Draws(200); ++draw) {
    const Eigen::Isometry3d truth = RandomPose(rng);
    std::vector<Eigen::Vector3d> src, dst;
    std::vector<Eigen::Matrix3d> src_cov, dst_cov;
    for (const auto& p : Layout()) {
      const Eigen::Vector3d s_sigma(0.01, 0.02, 0.05), d_sigma(0.05, 0.05, 0.05);
      src.push_back(p + Eigen::Vector3d{rng.Normal() * s_sigma.x(), rng.Normal() * s_sigma.y(),
                                        rng.Normal() * s_sigma.z()});
      dst.push_back(truth * p + Eigen::Vector3d{rng.Normal() * d_sigma.x(),
                                                rng.Normal() * d_sigma.y(),
                                                rng.Normal() * d_sigma.z()});
      src_cov.push_back(s_sigma.cwiseAbs2().asDiagonal());
      dst_cov.push_back(d_sigma.cwiseAbs2().asDiagonal());
    }
    const RigidFitResult r = FitRigidTransform(src, dst, src_cov, dst_cov);
    // truth = Exp(xi) * estimate
    const Vector6d xi = RotationVectorTranslation(truth * r.target_from_source.inverse());
    for (int k = 0; k < 6; ++k) {
      inside += std::abs(xi[k]) <= std::sqrt(r.covariance(k, k));
      ++total;
    }
  }
  const double fraction = static_cast<double>(inside) / total;
  std::printf("[ measured ] rigid fit 1-sigma coverage: %.3f over %d\n", fraction, total);
  if (!lasercell::test::StatisticsAsserted()) return;
  EXPECT_GE(fraction, 0.60);
  EXPECT_LE(fraction, 0.76);
}

TEST(FitRigidTransform, FewerThanThreePointsNameTheDegeneracy) {
  RigidFitOptions o;
  o.item_name = "sphere";
  try {
    FitRigidTransform({{0, 0, 0}, {100, 0, 0}}, {{0, 0, 0}, {100, 0, 0}}, {}, {}, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "rigid fit: 2 spheres: a rigid transform needs at least 3 non-collinear spheres "
                 "(with 2 the rotation about their line is unobservable)");
  }
}

TEST(FitRigidTransform, CollinearPointsNameTheDegeneracy) {
  const std::vector<Eigen::Vector3d> line = {
      {0, 0, 0}, {100, 0, 0.2}, {250, 0, -0.1}, {400, 0.1, 0}};
  try {
    FitRigidTransform(line, line);
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("the 4 points are collinear"), std::string::npos) << m;
    EXPECT_NE(m.find("rotation about that line is unobservable"), std::string::npos) << m;
  }
}

// The closed form refuses input that cannot determine a rotation instead of returning garbage.
TEST(HornRigidTransform, DegenerateInputIsAnInputErrorNamingIt) {
  const std::vector<Eigen::Vector3d> two = {{0, 0, 0}, {100, 0, 0}};
  try {
    HornRigidTransform(two, two);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 points: a rigid transform needs at least 3"),
              std::string::npos)
        << e.what();
  }
  const auto src = Layout();
  EXPECT_THROW(HornRigidTransform(src, {src[0], src[1], src[2]}), InputError);
  EXPECT_THROW(HornRigidTransform(src, src, {1.0, 1.0}), InputError);
  EXPECT_THROW(HornRigidTransform(src, src, std::vector<double>(src.size(), 0.0)), InputError);
  EXPECT_NO_THROW(HornRigidTransform(src, src));
}

TEST(FitRigidTransform, MismatchedCountsAndBadCovariancesThrow) {
  const auto src = Layout();
  EXPECT_THROW(FitRigidTransform(src, {src[0], src[1], src[2]}), InputError);
  std::vector<Eigen::Matrix3d> cov(4, Eigen::Matrix3d::Identity());
  cov[2] = -Eigen::Matrix3d::Identity();
  try {
    FitRigidTransform(src, src, cov, {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("source covariance of point 2 is not positive definite"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lasercell::calib
