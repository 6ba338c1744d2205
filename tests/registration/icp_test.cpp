#include "registration/icp.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "registration_test_util.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

// An irregular, well-conditioned target: a sphere resting on a box, exact normals.
PointCloud TargetShape(std::mt19937_64& rng, std::size_t sphere_points) {
  PointCloud target = test::BoxPoints({40, 30, 15}, 1.5);
  target.Append(test::SpherePoints(sphere_points, 25.0, {10, 5, 35}, rng));
  return target;
}

struct Problem {
  KdTree tree;
  std::vector<Eigen::Vector3d> normals;
  std::vector<Eigen::Vector3d> source;   // in the source frame
  Eigen::Isometry3d target_from_source;  // truth
};

// Source = freshly sampled surface points (not the target's), moved by the inverse truth,
// with Gaussian noise and a fraction of outliers near the surface.
Problem MakeProblem(std::uint64_t seed, double noise_mm, double outlier_fraction) {
  std::mt19937_64 rng(seed);
  Problem problem;
  PointCloud target = TargetShape(rng, 6000);
  problem.normals = target.normals;
  problem.tree = KdTree(target.positions);
  problem.target_from_source = PoseFromRotationVector({0.3, -0.2, 0.5}, {100, -50, 400});
  PointCloud surface = test::BoxPoints({40, 30, 15}, 2.3);
  surface.Append(test::SpherePoints(1500, 25.0, {10, 5, 35}, rng));
  std::normal_distribution<double> g(0.0, noise_mm);
  std::uniform_real_distribution<double> u(0.0, 1.0), offset(2.0, 6.0);
  const Eigen::Isometry3d source_from_target = problem.target_from_source.inverse();
  for (std::size_t i = 0; i < surface.size(); ++i) {
    Eigen::Vector3d p = surface.positions[i] + g(rng) * surface.normals[i];
    if (u(rng) < outlier_fraction)
      p += offset(rng) * surface.normals[i];  // clutter just above the surface
    problem.source.push_back(source_from_target * p);
  }
  return problem;
}

IcpResult AlignFromPerturbed(const Problem& p, const IcpOptions& options, std::uint64_t seed = 7) {
  std::mt19937_64 rng(seed);
  const Eigen::Isometry3d start = test::RandomPerturbation(rng, 0.08, 6.0) * p.target_from_source;
  return AlignIcp(p.source, p.tree, p.normals, start, options);
}

TEST(IcpTest, PointToPlaneRecoversThePoseWithinTheNoise) {
  const Problem p = MakeProblem(61, 0.2, 0.0);
  const IcpResult result = AlignFromPerturbed(p, IcpOptions{});
  EXPECT_TRUE(result.converged) << result.Summary();
  EXPECT_EQ(result.termination, IcpTermination::kConverged);
  // ~5000 points with sigma 0.2 mm: the points are placed to a few hundredths of a mm.
  EXPECT_LT(test::PoseRmsMm(p.source, result.target_from_source, p.target_from_source), 0.03);
  EXPECT_NEAR(result.rmse_mm, 0.2, 0.05);  // the residual is the noise
  EXPECT_GT(result.inlier_fraction, 0.95);
  EXPECT_LT(result.iterations, 20);
  EXPECT_THAT(result.Summary(), HasSubstr("converged"));
}

TEST(IcpTest, PointToPointRecoversThePose) {
  const Problem p = MakeProblem(62, 0.2, 0.0);
  IcpOptions options;
  options.metric = IcpMetric::kPointToPoint;
  options.max_iterations = 100;
  const IcpResult result = AlignFromPerturbed(p, options);
  EXPECT_TRUE(result.converged) << result.Summary();
  // Point-to-point is biased by the 1.5 mm target spacing: looser than point-to-plane.
  EXPECT_LT(test::PoseRmsMm(p.source, result.target_from_source, p.target_from_source), 0.2);
}

TEST(IcpTest, RobustKernelsResistClutterNearTheSurface) {
  const Problem p = MakeProblem(63, 0.2, 0.2);
  IcpOptions options;
  options.kernel = RobustKernel::kNone;
  const IcpResult plain = AlignFromPerturbed(p, options);
  const double plain_error =
      test::PoseRmsMm(p.source, plain.target_from_source, p.target_from_source);
  for (RobustKernel kernel :
       {RobustKernel::kTukey, RobustKernel::kGemanMcClure, RobustKernel::kHuber}) {
    options.kernel = kernel;
    const IcpResult robust = AlignFromPerturbed(p, options);
    const double error = test::PoseRmsMm(p.source, robust.target_from_source, p.target_from_source);
    EXPECT_LT(error, 0.5 * plain_error)
        << "kernel " << static_cast<int>(kernel) << ": " << error << " vs " << plain_error;
    if (kernel !=
        RobustKernel::kHuber) {  // redescending kernels ignore the clutter almost entirely
      EXPECT_LT(error, 0.06) << "kernel " << static_cast<int>(kernel);
    }
  }
  EXPECT_GT(plain_error, 0.12);  // the clutter does pull least squares away (0.17 mm here)
}

TEST(IcpTest, IdenticalForAnyThreadCount) {
  const Problem p = MakeProblem(64, 0.3, 0.1);
  IcpOptions options;
  options.threads = 1;
  const IcpResult one = AlignFromPerturbed(p, options);
  options.threads = 2;
  const IcpResult two = AlignFromPerturbed(p, options);
  options.threads = 0;
  const IcpResult all = AlignFromPerturbed(p, options);
  EXPECT_EQ(one.target_from_source.matrix(), two.target_from_source.matrix());
  EXPECT_EQ(one.target_from_source.matrix(), all.target_from_source.matrix());
  EXPECT_EQ(one.iterations, two.iterations);
  EXPECT_EQ(one.rmse_mm, two.rmse_mm);
}

TEST(IcpTest, ReportsTooFewCorrespondencesAndDegeneracy) {
  const Problem p = MakeProblem(65, 0.2, 0.0);
  const Eigen::Isometry3d far =
      PoseFromRotationVector(Eigen::Vector3d::Zero(), {1000, 0, 0}) * p.target_from_source;
  const IcpResult lost = AlignIcp(p.source, p.tree, p.normals, far, IcpOptions{});
  EXPECT_FALSE(lost.converged);
  EXPECT_EQ(lost.termination, IcpTermination::kTooFewCorrespondences);
  EXPECT_STREQ(ToString(lost.termination), "too_few_correspondences");
  EXPECT_TRUE(lost.target_from_source.isApprox(far));  // the pose is left where it was

  // A plane: only the offset along its normal (and two tilts) are observable.
  std::vector<Eigen::Vector3d> plane, normals, source;
  for (int x = -30; x <= 30; ++x) {
    for (int y = -30; y <= 30; ++y) {
      plane.push_back({x * 1.0, y * 1.0, 0.0});
      normals.push_back(Eigen::Vector3d::UnitZ());
      source.push_back({x * 1.0 + 0.5, y * 1.0 + 0.5, 2.0});
    }
  }
  const KdTree tree(plane);
  const IcpResult flat =
      AlignIcp(source, tree, normals, Eigen::Isometry3d::Identity(), IcpOptions{});
  EXPECT_TRUE(flat.converged) << flat.Summary();
  EXPECT_TRUE(flat.degenerate);
  EXPECT_NEAR(flat.target_from_source.translation().z(), -2.0, 1e-6);
  EXPECT_NEAR(flat.target_from_source.translation().head<2>().norm(), 0.0,
              1e-3);  // damped, not drifting
}

TEST(IcpTest, NormalCompatibilityDropsPairsAcrossAnEdge) {
  // A step: the top face z = 0 (x <= 0) and the wall x = 0 below it (z < 0), as a model's
  // refinement points. The scan sees the top face only, and its last column overhangs the edge
  // by 0.6 mm (an edge's mixed pixels): those points' nearest model points are on the wall.
  std::vector<Eigen::Vector3d> model, model_normals, scan, scan_normals;
  for (int y = -20; y <= 20; ++y) {
    for (int x = -30; x <= 0; ++x) {
      model.push_back({x * 1.0, y * 1.0, 0.0});
      model_normals.push_back(Eigen::Vector3d::UnitZ());
    }
    for (int z = 1; z <= 20; ++z) {
      model.push_back({0.0, y * 1.0, -z * 1.0});
      model_normals.push_back(Eigen::Vector3d::UnitX());
    }
    for (int x = -30; x <= 0; ++x) {
      scan.push_back({x * 1.0 + 0.6, y * 1.0, -0.7});
      // The scanner's normals point back at it: flipped against the model's (still compatible).
      scan_normals.push_back(-Eigen::Vector3d::UnitZ());
    }
  }
  const KdTree tree(model);
  IcpOptions options;
  options.max_iterations = 1;
  options.kernel = RobustKernel::kNone;
  const IcpResult plain =
      AlignIcp(scan, tree, model_normals, Eigen::Isometry3d::Identity(), options, scan_normals);
  EXPECT_EQ(IcpOptions{}.max_normal_angle_rad, 0.0);  // off unless asked for
  options.max_normal_angle_rad = M_PI / 4;
  const IcpResult tested =
      AlignIcp(scan, tree, model_normals, Eigen::Isometry3d::Identity(), options, scan_normals);
  // Without the test the overhanging column (41 points) matches the wall and pulls the scan
  // back along x; with it those pairs are dropped, and x is left alone.
  EXPECT_LT(plain.target_from_source.translation().x(), -0.05);
  EXPECT_NEAR(tested.target_from_source.translation().x(), 0.0, 1e-6);
  EXPECT_NEAR(tested.target_from_source.translation().z(), 0.7, 1e-6);

  options.max_normal_angle_rad = 2.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("max_normal_angle_rad")));
  options.max_normal_angle_rad = M_PI / 4;
  const std::vector<Eigen::Vector3d> too_few(3, Eigen::Vector3d::UnitZ());
  EXPECT_THAT(
      [&] { AlignIcp(scan, tree, model_normals, Eigen::Isometry3d::Identity(), options, too_few); },
      ::testing::ThrowsMessage<InputError>(HasSubstr("one normal per source and target point")));
}

TEST(IcpTest, RejectsBadOptionsAndInput) {
  IcpOptions options;
  options.max_correspondence_distance_mm = 0.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("max_correspondence_distance_mm")));
  options = {};
  options.max_iterations = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("max_iterations")));
  options = {};
  options.kernel_scale_mm = -1.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("kernel_scale_mm")));
  const KdTree tree(std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  const std::vector<Eigen::Vector3d> source = {{0, 0, 0}};
  EXPECT_THAT(
      [&] { AlignIcp(source, tree, {}, Eigen::Isometry3d::Identity(), IcpOptions{}); },
      ::testing::ThrowsMessage<InputError>(HasSubstr("one target normal per target point")));
}

}  // namespace
}  // namespace lasercell::registration
