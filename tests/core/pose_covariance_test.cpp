// Pose covariance algebra (core/pose_covariance.hpp) and FrameGraph::TransformWithCovariance:
// exact identities of the SE(3) exponential and adjoint, and Monte-Carlo checks of the
// first-order propagation (seeded draws of the edges' perturbations, sample covariance of the
// composed pose's error against the predicted covariance).

#include "core/pose_covariance.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/kinematics.hpp"
#include "core/random.hpp"

namespace lasercell {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

Eigen::Isometry3d RandomPose(std::mt19937& rng, double half_mm) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> angle(0.0, 3.0), t(-half_mm, half_mm);
  const Eigen::Vector3d axis = Draws<3>(n, rng).normalized();
  return PoseFromRotationVector(angle(rng) * axis, Draws<3>(t, rng));
}

// A random full-rank covariance with correlations: rotation sigmas about `rot_rad`,
// translation sigmas about `trans_mm`.
Matrix6d RandomCovariance(std::mt19937& rng, double rot_rad, double trans_mm) {
  std::normal_distribution<double> n(0.0, 1.0);
  Matrix6d a;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) a(r, c) = n(rng) * (r < 3 ? rot_rad : trans_mm);
  }
  const Matrix6d cov = a * a.transpose() / 6.0;
  return 0.5 * (cov + cov.transpose());
}

// Draws xi ~ N(0, cov).
class GaussianSampler {
 public:
  explicit GaussianSampler(const Matrix6d& cov) : l_(cov.llt().matrixL()) {}
  Vector6d operator()(std::mt19937& rng) {
    Vector6d z;
    for (int k = 0; k < 6; ++k) z(k) = normal_(rng);
    return l_ * z;
  }

 private:
  Matrix6d l_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

template <int N>
Eigen::Matrix<double, N, N> SampleCovariance(const std::vector<Eigen::Matrix<double, N, 1>>& x) {
  Eigen::Matrix<double, N, 1> mean = Eigen::Matrix<double, N, 1>::Zero();
  for (const auto& v : x) mean += v;
  mean /= static_cast<double>(x.size());
  Eigen::Matrix<double, N, N> cov = Eigen::Matrix<double, N, N>::Zero();
  for (const auto& v : x) cov += (v - mean) * (v - mean).transpose();
  return cov / static_cast<double>(x.size() - 1);
}

double RelativeFrobenius(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  return (actual - expected).norm() / expected.norm();
}

TEST(PoseCovarianceTest, ExpAndLogAreInverse) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (const double angle : {0.0, 1e-9, 1e-4, 5e-3, 2e-2, 0.7, 2.0, 3.1}) {
    for (int trial = 0; trial < 20; ++trial) {
      Vector6d xi;
      xi.head<3>() = Draws<3>(n, rng).normalized() * angle;
      xi.tail<3>() = 300.0 * Draws<3>(n, rng);
      const Vector6d back = LogSe3(ExpSe3(xi));
      EXPECT_LT((back - xi).head<3>().norm(), 1e-12) << "angle " << angle;
      EXPECT_LT((back - xi).tail<3>().norm(), 1e-12 * 300.0) << "angle " << angle;
    }
  }
  // The translation of Exp is V(w) u, not u: a quarter turn about z moving 1 mm along x ends
  // on the arc, at (sin(a)/a, (1 - cos(a))/a, 0) mm.
  Vector6d quarter;
  quarter << 0, 0, std::numbers::pi / 2, 1, 0, 0;
  const double a = std::numbers::pi / 2;
  EXPECT_NEAR(ExpSe3(quarter).translation().x(), std::sin(a) / a, 1e-15);
  EXPECT_NEAR(ExpSe3(quarter).translation().y(), (1.0 - std::cos(a)) / a, 1e-15);
}

TEST(PoseCovarianceTest, AdjointMovesAPerturbationAcrossAPose) {
  std::mt19937 rng(12);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Isometry3d t = RandomPose(rng, 500.0);
    Vector6d xi;
    xi << 0.3 * n(rng), 0.3 * n(rng), 0.3 * n(rng), 20 * n(rng), 20 * n(rng), 20 * n(rng);
    // Exp(Ad(T) xi) = T Exp(xi) T^-1, to round-off (entries up to ~1000 mm: relative 1e-12).
    const Eigen::Matrix4d lhs = ExpSe3(Adjoint(t) * xi).matrix();
    const Eigen::Matrix4d rhs = (t * ExpSe3(xi) * t.inverse()).matrix();
    EXPECT_LT((lhs.topLeftCorner<3, 3>() - rhs.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((lhs.topRightCorner<3, 1>() - rhs.topRightCorner<3, 1>()).norm(),
              1e-12 * (1.0 + rhs.topRightCorner<3, 1>().norm()));
    // A group homomorphism: Ad(a b) = Ad(a) Ad(b), Ad(T^-1) = Ad(T)^-1.
    const Eigen::Isometry3d u = RandomPose(rng, 500.0);
    EXPECT_LT((Adjoint(t * u) - Adjoint(t) * Adjoint(u)).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((Adjoint(t.inverse()) * Adjoint(t) - Matrix6d::Identity()).cwiseAbs().maxCoeff(),
              1e-9);
  }
}

TEST(PoseCovarianceTest, ComposeAndInverseAgreeWithTheirDefinitions) {
  std::mt19937 rng(13);
  const Eigen::Isometry3d a = RandomPose(rng, 400.0);
  const Matrix6d cov_a = RandomCovariance(rng, 1e-3, 0.2);
  const Matrix6d cov_b = RandomCovariance(rng, 2e-3, 0.1);
  // Composing with an exact identity adds the covariances.
  EXPECT_LT((ComposeCovariance(Eigen::Isometry3d::Identity(), cov_a, cov_b) - (cov_a + cov_b))
                .cwiseAbs()
                .maxCoeff(),
            1e-15);
  // Inverting twice returns the covariance; t * t^-1 = I is exact, so the two covariances of
  // t and of t^-1 (fully correlated, not independent) must not simply be composed: check only
  // the round trip and the rotation block (Ad(t^-1) rotates it by R^T).
  const Matrix6d inv = InverseCovariance(a, cov_a);
  EXPECT_LT((InverseCovariance(a.inverse(), inv) - cov_a).norm(), 1e-12 * cov_a.norm());
  const Eigen::Matrix3d r = a.linear();
  EXPECT_LT((inv.topLeftCorner<3, 3>() - r.transpose() * cov_a.topLeftCorner<3, 3>() * r).norm(),
            1e-15);
  EXPECT_EQ(inv, inv.transpose());
}

TEST(PoseCovarianceTest, PointCovarianceMatchesMonteCarlo) {
  std::mt19937 rng(14);
  const Eigen::Isometry3d t = RandomPose(rng, 400.0);
  const Matrix6d cov = RandomCovariance(rng, 2e-3, 0.3);
  const Eigen::Vector3d p(120.0, -80.0, 300.0);
  GaussianSampler sample(cov);
  std::vector<Eigen::Vector3d> q;
  for (int i = 0; i < 20000; ++i) q.push_back(ExpSe3(sample(rng)) * t * p);
  const Eigen::Matrix3d predicted = PointCovariance(t, cov, p);
  const double error = RelativeFrobenius(SampleCovariance<3>(q), predicted);
  RecordProperty("relative_frobenius_error", std::to_string(error));
  EXPECT_LT(error, 0.05);
  // The lever arm matters: without it the prediction would be the translation block alone.
  EXPECT_GT(RelativeFrobenius(cov.bottomRightCorner<3, 3>(), predicted), 0.5);
}

TEST(PoseCovarianceTest, SigmasAreSquareRootsOfTheDiagonal) {
  Vector6d diag;
  diag << 1e-6, 4e-6, 9e-6, 0.01, 0.04, -1e-20;  // the last: round-off below zero
  const Matrix6d cov = diag.asDiagonal();
  const Vector6d sigma = PoseSigma(cov);
  EXPECT_NEAR(sigma(1), 2e-3, 1e-15);
  EXPECT_NEAR(sigma(4), 0.2, 1e-15);
  EXPECT_EQ(sigma(5), 0.0);
  EXPECT_NEAR(RotationSigmaDeg(cov)(2), 3e-3 * 180.0 / std::numbers::pi, 1e-12);
  EXPECT_NEAR(TranslationSigmaMm(cov)(0), 0.1, 1e-15);
  Matrix6d bad = cov;
  bad(0, 0) = std::nan("");
  EXPECT_TRUE(std::isnan(PoseSigma(bad)(0)));  // never hidden as 0
}

StaticEdge EdgeWithCovariance(const std::string& parent, const std::string& child,
                              const Eigen::Isometry3d& parent_from_child,
                              std::optional<Matrix6d> covariance) {
  StaticEdge edge;
  edge.parent = parent;
  edge.child = child;
  edge.SetParentFromChild(parent_from_child);
  edge.covariance = covariance;
  return edge;
}

// cell <- handling_base <- tool, and sensor <- tool reversed (the path from handling_base to
// sensor walks it child -> parent). Each edge's perturbation is drawn independently.
TEST(PoseCovarianceTest, FrameGraphCovarianceMatchesMonteCarloAlongAPath) {
  std::mt19937 rng(15);
  const Eigen::Isometry3d cell_from_base = RandomPose(rng, 800.0);
  const Eigen::Isometry3d base_from_tool = RandomPose(rng, 500.0);
  const Eigen::Isometry3d sensor_from_tool = RandomPose(rng, 300.0);
  const Matrix6d c1 = RandomCovariance(rng, 1e-3, 0.2);
  const Matrix6d c2 = RandomCovariance(rng, 2e-3, 0.1);
  const Matrix6d c3 = RandomCovariance(rng, 1.5e-3, 0.3);
  FrameGraph graph;
  graph.SetStaticEdge(EdgeWithCovariance("cell", "handling_base", cell_from_base, c1));
  graph.SetStaticEdge(EdgeWithCovariance("handling_base", "tool", base_from_tool, c2));
  graph.SetStaticEdge(EdgeWithCovariance("sensor", "tool", sensor_from_tool, c3));

  const TransformWithCovarianceResult result = graph.TransformWithCovariance("cell", "sensor");
  const Eigen::Isometry3d nominal = cell_from_base * base_from_tool * sensor_from_tool.inverse();
  EXPECT_EQ(result.to_from_from.matrix(), graph.Transform("cell", "sensor").matrix());
  EXPECT_TRUE(result.to_from_from.isApprox(nominal, 1e-12));
  EXPECT_TRUE(result.Complete());
  EXPECT_TRUE(result.edges_without_covariance.empty());
  EXPECT_FALSE(result.crosses_dynamic_edge);

  GaussianSampler s1(c1), s2(c2), s3(c3);
  std::vector<Vector6d> errors;
  for (int i = 0; i < 20000; ++i) {
    const Vector6d e1 = s1(rng), e2 = s2(rng), e3 = s3(rng);
    const Eigen::Isometry3d sampled = (ExpSe3(e1) * cell_from_base) *
                                      (ExpSe3(e2) * base_from_tool) *
                                      (ExpSe3(e3) * sensor_from_tool).inverse();
    errors.push_back(LogSe3(sampled * nominal.inverse()));
  }
  const Matrix6d sample = SampleCovariance<6>(errors);
  const double error = RelativeFrobenius(sample, result.covariance);
  RecordProperty("relative_frobenius_error", std::to_string(error));
  EXPECT_LT(error, 0.05) << "sample\n" << sample << "\npredicted\n" << result.covariance;
  // Not a test that passes for any covariance: walking the third edge forward (ignoring that it
  // is reversed) or dropping the lever arms gives a matrix well outside the tolerance.
  const Matrix6d wrong = ComposeCovariance(cell_from_base * base_from_tool,
                                           ComposeCovariance(cell_from_base, c1, c2), c3);
  EXPECT_GT(RelativeFrobenius(sample, wrong), 0.1);
  EXPECT_GT(RelativeFrobenius(sample, c1 + c2 + c3), 0.1);
}

TEST(PoseCovarianceTest, FrameGraphNamesWhatItsCovarianceLeavesOut) {
  std::mt19937 rng(16);
  const Matrix6d c = RandomCovariance(rng, 1e-3, 0.2);
  FrameGraph graph;
  graph.SetRobot("vision_robot", NominalUr5());
  graph.SetStaticEdge(EdgeWithCovariance("cell", "handling_base", RandomPose(rng, 500), c));
  graph.SetStaticEdge(EdgeWithCovariance("cell", "vision_base", RandomPose(rng, 500), {}));
  graph.SetDynamicEdge({"vision_base", "vision_flange", "vision_robot"});
  graph.SetStaticEdge(EdgeWithCovariance("vision_flange", "sensor", RandomPose(rng, 100), c));
  const JointValues joints = {{"vision_robot", {0.1, -1.2, 1.4, -0.3, 1.5, 0.2}}};

  const auto result = graph.TransformWithCovariance("handling_base", "sensor", joints);
  EXPECT_EQ(result.to_from_from.matrix(),
            graph.Transform("handling_base", "sensor", joints).matrix());
  EXPECT_THAT(result.edges_without_covariance, ElementsAre("cell <- vision_base"));
  EXPECT_TRUE(result.crosses_dynamic_edge);
  EXPECT_THAT(result.robots_on_path, ElementsAre("vision_robot"));
  EXPECT_FALSE(result.Complete());
  EXPECT_THAT(result.Summary(), HasSubstr("static edge cell <- vision_base (no covariance)"));
  EXPECT_THAT(result.Summary(), HasSubstr("robot vision_robot (joint and kinematic"));
  // Both covariances contribute: the handling_base edge walked backwards, the hand-eye moved
  // through the robot's pose.
  const Eigen::Isometry3d base_from_cell = graph.Transform("handling_base", "cell");
  const Eigen::Isometry3d base_from_flange =
      graph.Transform("handling_base", "vision_flange", joints);
  const Matrix6d expected =
      ComposeCovariance(base_from_flange, InverseCovariance(base_from_cell.inverse(), c), c);
  EXPECT_LT((result.covariance - expected).norm(), 1e-9 * expected.norm());

  // A path over edges with covariance only, and the trivial path.
  EXPECT_TRUE(graph.TransformWithCovariance("cell", "handling_base").Complete());
  EXPECT_EQ(graph.TransformWithCovariance("cell", "handling_base").covariance, c);
  const auto same = graph.TransformWithCovariance("sensor", "sensor");
  EXPECT_EQ(same.covariance, Matrix6d::Zero());
  EXPECT_EQ(same.Summary(), "covariance covers every edge on the path");
}

TEST(PoseCovarianceTest, FrameGraphQueryRejectsWhatTransformRejects) {
  FrameGraph graph;
  graph.SetRobot("vision_robot", NominalUr5());
  graph.SetDynamicEdge({"vision_base", "vision_flange", "vision_robot"});
  graph.AddFrame("island");
  EXPECT_THAT([&] { graph.TransformWithCovariance("vision_base", "ghost"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("unknown frame 'ghost'")));
  EXPECT_THAT([&] { graph.TransformWithCovariance("vision_base", "island"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("not connected")));
  EXPECT_THAT([&] { graph.TransformWithCovariance("vision_base", "vision_flange"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("joints[\"vision_robot\"]")));
}

}  // namespace
}  // namespace lasercell
