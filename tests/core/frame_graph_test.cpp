// FrameGraph: property tests on seeded random trees (inverse, composition, cycles) against
// ground-truth world poses, edge replacement, dynamic edges through the UR5, the stored
// quaternion form of static edges (canonical sign, kept as given), and errors.

#include "core/frame_graph.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/random.hpp"

namespace lasercell {
namespace {

using ::testing::HasSubstr;

::testing::AssertionResult PosesNear(const Eigen::Isometry3d& actual,
                                     const Eigen::Isometry3d& expected, double tolerance) {
  const double diff =
      (actual.matrix().topRows<3>() - expected.matrix().topRows<3>()).cwiseAbs().maxCoeff();
  if (diff <= tolerance) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max |difference| " << diff << " > " << tolerance;
}

Eigen::Isometry3d RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d axis = Draws<3>(n, rng).normalized();
  return PoseFromQuaternion(Eigen::Quaterniond(Eigen::AngleAxisd(3.0 * n(rng), axis)),
                            500.0 * Draws<3>(n, rng));
}

StaticEdge Edge(const std::string& parent, const std::string& child,
                const Eigen::Isometry3d& parent_from_child, const std::string& tool = "test") {
  StaticEdge edge;
  edge.parent = parent;
  edge.child = child;
  edge.SetParentFromChild(parent_from_child);
  edge.provenance.tool = tool;
  return edge;
}

/// True when both edges store the very same bits for rotation and translation.
bool SamePoseBits(const StaticEdge& a, const StaticEdge& b) {
  const QuaternionPose &x = a.parent_from_child, &y = b.parent_from_child;
  return std::memcmp(x.rotation.coeffs().data(), y.rotation.coeffs().data(), 4 * sizeof(double)) ==
             0 &&
         std::memcmp(x.translation_mm.data(), y.translation_mm.data(), 3 * sizeof(double)) == 0;
}

/// A random tree: frame_i (i > 0) hangs off a random earlier frame, in a random direction;
/// world_from[i] is each frame's ground-truth pose.
struct RandomTree {
  FrameGraph graph;
  std::vector<std::string> names;
  std::vector<Eigen::Isometry3d> world_from;
};

RandomTree MakeRandomTree(std::mt19937& rng, int frames) {
  RandomTree tree;
  for (int i = 0; i < frames; ++i) {
    tree.names.push_back("frame_" + std::to_string(i));
    tree.world_from.push_back(RandomPose(rng));
  }
  tree.graph.AddFrame(tree.names[0]);
  for (int i = 1; i < frames; ++i) {
    const int j = std::uniform_int_distribution<int>(0, i - 1)(rng);
    const bool down = std::bernoulli_distribution(0.5)(rng);
    const int parent = down ? j : i, child = down ? i : j;
    tree.graph.SetStaticEdge(Edge(tree.names[parent], tree.names[child],
                                  tree.world_from[parent].inverse() * tree.world_from[child]));
  }
  return tree;
}

// UR5 forward kinematics from elementary transforms, independent of DhChain.
Eigen::Isometry3d Ur5Reference(const std::vector<double>& q) {
  constexpr double kPi = std::numbers::pi;
  const double d[6] = {89.159, 0, 0, 109.15, 94.65, 82.3};
  const double a[6] = {0, -425.0, -392.25, 0, 0, 0};
  const double alpha[6] = {kPi / 2, 0, 0, kPi / 2, -kPi / 2, 0};
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) {
    t = t * Eigen::AngleAxisd(q[i], Eigen::Vector3d::UnitZ()) *
        Eigen::Translation3d(a[i], 0, d[i]) * Eigen::AngleAxisd(alpha[i], Eigen::Vector3d::UnitX());
  }
  return t;
}

TEST(FrameGraphTest, FrameNamesAreLowerSnakeCaseAndSorted) {
  FrameGraph graph;
  graph.AddFrame("vision_flange");
  graph.AddFrame("camera");
  graph.AddFrame("camera");  // no-op
  graph.AddFrame("part_2");
  EXPECT_EQ(graph.Frames(), (std::vector<std::string>{"camera", "part_2", "vision_flange"}));
  EXPECT_TRUE(graph.HasFrame("camera"));
  EXPECT_FALSE(graph.HasFrame("sensor"));
  for (const std::string bad : {"Camera", "2nd", "", "vision-flange", "a b", "_x"}) {
    try {
      graph.AddFrame(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("'" + bad + "' is not lower snake case"));
    }
  }
  EXPECT_THROW(graph.SetStaticEdge(Edge("Camera", "sensor", Eigen::Isometry3d::Identity())),
               InputError);
  EXPECT_EQ(graph.Frames().size(), 3u);
}

TEST(FrameGraphTest, RandomTreesMatchGroundTruthAndComposeAndInvert) {
  std::mt19937 rng(2024);
  for (int tree_index = 0; tree_index < 20; ++tree_index) {
    const RandomTree tree = MakeRandomTree(rng, 2 + tree_index);
    const int n = static_cast<int>(tree.names.size());
    std::uniform_int_distribution<int> pick(0, n - 1);
    for (int trial = 0; trial < 30; ++trial) {
      const int a = pick(rng), b = pick(rng), c = pick(rng);
      const Eigen::Isometry3d a_from_b = tree.graph.Transform(tree.names[a], tree.names[b]);
      const Eigen::Isometry3d b_from_a = tree.graph.Transform(tree.names[b], tree.names[a]);
      const Eigen::Isometry3d b_from_c = tree.graph.Transform(tree.names[b], tree.names[c]);
      const Eigen::Isometry3d a_from_c = tree.graph.Transform(tree.names[a], tree.names[c]);
      // Ground truth: a_from_b = world_from_a^-1 * world_from_b.
      EXPECT_TRUE(PosesNear(a_from_b, tree.world_from[a].inverse() * tree.world_from[b], 1e-9));
      // Inverse round trip and path composition.
      EXPECT_TRUE(PosesNear(a_from_b * b_from_a, Eigen::Isometry3d::Identity(), 1e-9));
      EXPECT_TRUE(PosesNear(a_from_c, a_from_b * b_from_c, 1e-9));
      EXPECT_TRUE(tree.graph.Connected(tree.names[a], tree.names[c]));
    }
  }
}

TEST(FrameGraphTest, EdgesClosingACycleAreRejectedAndLeaveTheGraphUnchanged) {
  std::mt19937 rng(7);
  RandomTree tree = MakeRandomTree(rng, 10);
  const FrameGraph before = tree.graph;
  std::uniform_int_distribution<int> pick(0, 9);
  int rejected = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const int a = pick(rng), b = pick(rng);
    if (a == b) continue;
    bool adjacent = false;  // an existing edge between a and b is replaced, not a cycle
    for (const StaticEdge& e : tree.graph.static_edges()) {
      adjacent |= (e.parent == tree.names[a] && e.child == tree.names[b]) ||
                  (e.parent == tree.names[b] && e.child == tree.names[a]);
    }
    if (adjacent) continue;
    try {
      tree.graph.SetStaticEdge(Edge(tree.names[a], tree.names[b], RandomPose(rng)));
      ADD_FAILURE() << "accepted a cycle " << tree.names[a] << " - " << tree.names[b];
    } catch (const InputError& e) {
      ++rejected;
      EXPECT_THAT(e.what(),
                  HasSubstr("would create a cycle: " + tree.names[a] + " and " + tree.names[b] +
                            " are already connected via " + tree.names[a] + " -> "));
    }
  }
  EXPECT_GT(rejected, 20);
  ASSERT_EQ(tree.graph.static_edges().size(), before.static_edges().size());
  for (std::size_t i = 0; i < before.static_edges().size(); ++i) {
    EXPECT_TRUE(SamePoseBits(tree.graph.static_edges()[i], before.static_edges()[i])) << i;
  }
}

TEST(FrameGraphTest, ForestAllowsTwoParentsButNotConnectedQueriesFail) {
  FrameGraph graph;
  const Eigen::Isometry3d t(Eigen::Translation3d(1, 2, 3));
  graph.SetStaticEdge(Edge("a", "shared", t));
  graph.SetStaticEdge(Edge("b", "shared", t));  // second parent: joins two trees, no cycle
  graph.SetStaticEdge(Edge("a", "a_child", t));
  graph.SetStaticEdge(Edge("a", "a_other", t));  // several children
  graph.AddFrame("lonely");
  EXPECT_TRUE(PosesNear(graph.Transform("a", "b"), Eigen::Isometry3d::Identity(), 1e-12));
  EXPECT_TRUE(
      PosesNear(graph.Transform("a_child", "a_other"), Eigen::Isometry3d::Identity(), 1e-12));
  EXPECT_TRUE(PosesNear(graph.Transform("a", "a"), Eigen::Isometry3d::Identity(), 0.0));
  EXPECT_FALSE(graph.Connected("a", "lonely"));
  EXPECT_FALSE(graph.Connected("a", "nowhere"));
  try {
    graph.Transform("lonely", "a");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'lonely' and 'a' are not connected"));
  }
  try {
    graph.Transform("a", "nowhere");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown frame 'nowhere'; known frames: a, a_child, a_other, "
                                    "b, lonely, shared"));
  }
}

TEST(FrameGraphTest, ReplacingAnEdgeKeepsTheOthersUntouched) {
  std::mt19937 rng(3);
  RandomTree tree = MakeRandomTree(rng, 8);
  const std::vector<StaticEdge> before = tree.graph.static_edges();
  const std::size_t k = 4;
  // Replace edge k, given in the opposite direction: one tool updates only its own edge.
  const Eigen::Isometry3d new_child_from_parent = RandomPose(rng);
  StaticEdge replacement = Edge(before[k].child, before[k].parent, new_child_from_parent, "tool b");
  replacement.covariance = Matrix6d::Identity() * 0.01;
  tree.graph.SetStaticEdge(replacement);
  const std::vector<StaticEdge>& after = tree.graph.static_edges();
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < before.size(); ++i) {
    if (i == k) continue;
    EXPECT_EQ(after[i].parent, before[i].parent);
    EXPECT_EQ(after[i].child, before[i].child);
    EXPECT_TRUE(SamePoseBits(after[i], before[i])) << i;
    EXPECT_EQ(after[i].provenance.tool, "test");
  }
  EXPECT_EQ(after[k].parent, before[k].child);  // takes the new direction
  EXPECT_EQ(after[k].provenance.tool, "tool b");
  ASSERT_TRUE(after[k].covariance.has_value());
  EXPECT_TRUE(SamePoseBits(after[k], replacement));
  EXPECT_EQ(tree.graph.Transform(before[k].child, before[k].parent).matrix(),
            replacement.ParentFromChild().matrix());
  EXPECT_TRUE(PosesNear(tree.graph.Transform(before[k].child, before[k].parent),
                        new_child_from_parent, 1e-12));
}

TEST(FrameGraphTest, MatricesMustBeRigid) {
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 1.001;
  Eigen::Isometry3d mirrored = Eigen::Isometry3d::Identity();
  mirrored.linear() = Eigen::Vector3d(1, 1, -1).asDiagonal();
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().x() = std::nan("");
  for (const auto& [pose, problem] :
       {std::pair{scaled, "not orthonormal"}, std::pair{mirrored, "not orthonormal"},
        std::pair{nan, "non-finite"}}) {
    StaticEdge edge;
    edge.parent = "a";
    edge.child = "b";
    try {
      edge.SetParentFromChild(pose);
      ADD_FAILURE() << "accepted " << problem;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(problem));
      EXPECT_THAT(e.what(), HasSubstr("static edge a <- b parent_from_child"));
    }
    // The edge keeps its previous (identity) pose.
    EXPECT_EQ(edge.parent_from_child.rotation.coeffs(), Eigen::Quaterniond::Identity().coeffs());
    EXPECT_EQ(edge.parent_from_child.translation_mm, Eigen::Vector3d::Zero());
  }
  Eigen::Isometry3d almost = Eigen::Isometry3d::Identity();
  almost.linear()(0, 1) = 1e-12;
  FrameGraph graph;
  EXPECT_NO_THROW(graph.SetStaticEdge(Edge("a", "b", almost)));
  StaticEdge asymmetric = Edge("a", "c", Eigen::Isometry3d::Identity());
  asymmetric.covariance = Matrix6d::Identity();
  (*asymmetric.covariance)(0, 5) = 0.5;
  EXPECT_THROW(graph.SetStaticEdge(asymmetric), InputError);
  EXPECT_THROW(graph.SetStaticEdge(Edge("a", "a", Eigen::Isometry3d::Identity())), InputError);
}

TEST(FrameGraphTest, QuaternionsGivenDirectlyMustBeUnitAndFiniteAndAreKeptAsGiven) {
  FrameGraph graph;
  const auto edge_with = [](const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
    StaticEdge edge;
    edge.parent = "a";
    edge.child = "b";
    edge.parent_from_child = {q, t};
    return edge;
  };
  const Eigen::Vector3d t(1, 2, 3);
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& [edge, problem] :
       {std::pair{edge_with(Eigen::Quaterniond(1.001, 0, 0, 0), t), "rotation has norm 1.001"},
        std::pair{edge_with(Eigen::Quaterniond(0, 0, 0, 0), t), "rotation has norm 0"},
        std::pair{edge_with(Eigen::Quaterniond(1 + 2e-6, 0, 0, 0), t), "pass a unit quaternion"},
        std::pair{edge_with(Eigen::Quaterniond(std::nan(""), 0, 0, 0), t), "non-finite"},
        std::pair{edge_with(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, inf, 0)),
                  "non-finite"}}) {
    try {
      graph.SetStaticEdge(edge);
      ADD_FAILURE() << "accepted " << problem;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(problem));
      EXPECT_THAT(e.what(), HasSubstr("static edge a <- b parent_from_child"));
    }
  }
  EXPECT_TRUE(graph.Frames().empty());  // nothing added by a rejected edge
  // Within kUnitQuaternionTolerance (1e-6) of unit norm, any sign: stored bit for bit, normalized
  // only for the matrix.
  const Eigen::Quaterniond q(-(0.6 + 5e-10), 0.0, -0.0, 0.8);
  graph.SetStaticEdge(edge_with(q, t));
  const StaticEdge& stored = graph.static_edges()[0];
  const Eigen::Quaterniond& kept = stored.parent_from_child.rotation;
  EXPECT_EQ(std::memcmp(kept.coeffs().data(), q.coeffs().data(), 4 * sizeof(double)), 0);
  EXPECT_TRUE(std::signbit(kept.y()));
  const Eigen::Isometry3d matrix = stored.ParentFromChild();
  EXPECT_EQ(matrix.matrix(), PoseFromQuaternion(q, t).matrix());
  EXPECT_LT((matrix.linear().transpose() * matrix.linear() - Eigen::Matrix3d::Identity()).norm(),
            1e-15);
  EXPECT_TRUE(PosesNear(graph.Transform("a", "b"), matrix, 0.0));
}

TEST(FrameGraphTest, SetParentFromChildStoresTheCanonicalQuaternionOnce) {
  // CanonicalQuaternion itself (rotations by pi, -0) is tested in se3_test.cpp; here: the edge
  // stores exactly it, for both quaternion signs of the input, with the translation as given.
  std::mt19937 rng(12);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const Eigen::Quaterniond q = Eigen::Quaterniond{n(rng), n(rng), n(rng), n(rng)}.normalized();
    const Eigen::Isometry3d pose = PoseFromQuaternion(
        trial % 2 ? q : Eigen::Quaterniond(-q.coeffs()), 100.0 * Draws<3>(n, rng));
    StaticEdge edge;
    edge.SetParentFromChild(pose);
    ASSERT_EQ(edge.parent_from_child.rotation.coeffs(),
              CanonicalQuaternion(pose.linear()).coeffs());
    ASSERT_EQ(edge.parent_from_child.translation_mm, pose.translation());
    EXPECT_LT((edge.ParentFromChild().matrix() - pose.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

/// cell -> vision_base -(UR5)-> vision_flange -> sensor, plus cell -> handling_base.
FrameGraph MakeCell(std::mt19937& rng, Eigen::Isometry3d& cell_from_base,
                    Eigen::Isometry3d& flange_from_sensor, Eigen::Isometry3d& cell_from_handling) {
  FrameGraph graph;
  cell_from_base = RandomPose(rng);
  flange_from_sensor = RandomPose(rng);
  cell_from_handling = RandomPose(rng);
  graph.SetRobot("vision_robot", NominalUr5());
  graph.SetStaticEdge(Edge("cell", "vision_base", cell_from_base));
  graph.SetDynamicEdge({"vision_base", "vision_flange", "vision_robot"});
  graph.SetStaticEdge(Edge("vision_flange", "sensor", flange_from_sensor));
  graph.SetStaticEdge(Edge("cell", "handling_base", cell_from_handling));
  return graph;
}

TEST(FrameGraphTest, DynamicEdgeEvaluatesTheUr5Chain) {
  std::mt19937 rng(99);
  Eigen::Isometry3d cell_from_base, flange_from_sensor, cell_from_handling;
  const FrameGraph graph = MakeCell(rng, cell_from_base, flange_from_sensor, cell_from_handling);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<double> q(6);
    for (double& v : q) v = angle(rng);
    const JointValues joints = {{"vision_robot", q}, {"other_robot", {1.0}}};
    const Eigen::Isometry3d expected =
        cell_from_handling.inverse() * cell_from_base * Ur5Reference(q) * flange_from_sensor;
    EXPECT_TRUE(PosesNear(graph.Transform("handling_base", "sensor", joints), expected, 1e-6));
    EXPECT_TRUE(
        PosesNear(graph.Transform("sensor", "handling_base", joints), expected.inverse(), 1e-6));
  }
  EXPECT_EQ(graph.RobotsOnPath("handling_base", "sensor"),
            std::vector<std::string>{"vision_robot"});
  EXPECT_TRUE(graph.RobotsOnPath("handling_base", "vision_base").empty());
  // No joints are needed when the path avoids the robot.
  EXPECT_TRUE(PosesNear(graph.Transform("handling_base", "vision_base"),
                        cell_from_handling.inverse() * cell_from_base, 1e-9));
}

TEST(FrameGraphTest, MissingOrWrongJointValuesNameTheRobot) {
  std::mt19937 rng(1);
  Eigen::Isometry3d a, b, c;
  const FrameGraph graph = MakeCell(rng, a, b, c);
  for (const JointValues& joints :
       {JointValues{}, JointValues{{"vision_robot", {0.0, 0.0, 0.0}}}}) {
    try {
      graph.Transform("cell", "sensor", joints);
      ADD_FAILURE() << "no exception";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("robot 'vision_robot'"));
      EXPECT_THAT(e.what(), HasSubstr("needs 6 joint values"));
    }
  }
}

TEST(FrameGraphTest, DynamicEdgesNeedARegisteredRobotAndReplaceByRobot) {
  FrameGraph graph;
  EXPECT_THROW(graph.SetDynamicEdge({"base", "flange", "ghost"}), InputError);
  EXPECT_THROW(graph.Robot("ghost"), InputError);
  graph.SetRobot("arm", NominalUr5());
  graph.SetDynamicEdge({"base", "flange", "arm"});
  graph.SetDynamicEdge({"base", "tool0", "arm"});  // the robot's edge moves
  ASSERT_EQ(graph.dynamic_edges().size(), 1u);
  EXPECT_EQ(graph.dynamic_edges()[0].child, "tool0");
  EXPECT_FALSE(graph.Connected("base", "flange"));
  EXPECT_THROW(graph.SetStaticEdge(Edge("tool0", "base", Eigen::Isometry3d::Identity())),
               InputError);
  EXPECT_EQ(graph.Robots(), std::vector<std::string>{"arm"});
}

TEST(FrameGraphTest, CopiesAreDeepAndRemoveEdgeDisconnects) {
  std::mt19937 rng(5);
  Eigen::Isometry3d a, b, c;
  FrameGraph graph = MakeCell(rng, a, b, c);
  FrameGraph copy = graph;
  DhChain longer = NominalUr5();
  longer.mutable_joints()[1].a_mm = -600.0;
  copy.SetRobot("vision_robot", longer);
  const JointValues joints = {{"vision_robot", std::vector<double>(6, 0.0)}};
  EXPECT_FALSE(PosesNear(copy.Transform("cell", "sensor", joints),
                         graph.Transform("cell", "sensor", joints), 1.0));
  FrameGraph assigned;
  assigned = graph;
  EXPECT_TRUE(assigned.RemoveEdge("vision_flange", "vision_base"));
  EXPECT_FALSE(assigned.RemoveEdge("vision_flange", "vision_base"));
  EXPECT_FALSE(assigned.Connected("cell", "sensor"));
  EXPECT_TRUE(graph.Connected("cell", "sensor"));
  EXPECT_TRUE(assigned.RemoveEdge("sensor", "vision_flange"));
  EXPECT_EQ(assigned.static_edges().size(), 2u);
}

}  // namespace
}  // namespace lasercell
