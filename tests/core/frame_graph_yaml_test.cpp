// cell.yaml: exact text, bit-exact round trips on random cells (static edges and robots' mounts
// keep the file's quaternions), every rejected input with a message naming the file and the
// problem, and atomic saves.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/random.hpp"
#include "tests/cli_util.hpp"

namespace lasercell {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;
namespace fs = std::filesystem;

StaticEdge Edge(const std::string& parent, const std::string& child,
                const Eigen::Isometry3d& parent_from_child) {
  StaticEdge edge;
  edge.parent = parent;
  edge.child = child;
  edge.SetParentFromChild(parent_from_child);
  return edge;
}

/// True when a and b hold the very same bits (so also the same sign of zero).
template <typename A, typename B>
bool SameBits(const A& a, const B& b) {
  static_assert(sizeof(a) == sizeof(b));
  return std::memcmp(&a, &b, sizeof(a)) == 0;
}

::testing::AssertionResult SamePose(const QuaternionPose& a, const QuaternionPose& b) {
  if (SameBits(a.rotation.coeffs(), b.rotation.coeffs()) &&
      SameBits(a.translation_mm, b.translation_mm)) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure()
         << "rotation_wxyz " << a.rotation.w() << " " << a.rotation.vec().transpose() << " vs "
         << b.rotation.w() << " " << b.rotation.vec().transpose() << ", translation_mm "
         << a.translation_mm.transpose() << " vs " << b.translation_mm.transpose();
}

Eigen::Isometry3d RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Isometry3d pose(Eigen::AngleAxisd(3.0 * n(rng), Draws<3>(n, rng).normalized()));
  pose.translation() = 700.0 * Draws<3>(n, rng);
  return pose;
}

/// The example cell of the file format description.
FrameGraph ExampleCell() {
  FrameGraph graph;
  graph.AddFrame("camera");
  graph.SetRobot("vision_robot", NominalUr5());
  StaticEdge handeye =
      Edge("vision_flange", "sensor", Eigen::Isometry3d(Eigen::Translation3d(1.5, -2, 300)));
  handeye.provenance = {"lasercell calibrate handeye 0.1.0", "2026-11-26T10:00:00Z", "sha256:ab",
                        "rms \"0.021\" mm \\ 4 spheres"};
  graph.SetStaticEdge(handeye);
  Eigen::Isometry3d sensor_from_camera = Eigen::Isometry3d::Identity();
  sensor_from_camera.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();  // pi about x
  sensor_from_camera.translation() = Eigen::Vector3d(0, 0, 25);
  StaticEdge camera = Edge("sensor", "camera", sensor_from_camera);
  Matrix6d covariance = Matrix6d::Zero();
  covariance.diagonal() << 0.25, 0.25, 0.25, 4, 4, 4;
  covariance(0, 3) = covariance(3, 0) = 0.5;
  camera.covariance = covariance;
  graph.SetStaticEdge(camera);
  graph.SetDynamicEdge({"vision_base", "vision_flange", "vision_robot"});
  return graph;
}

constexpr const char* kExampleText = R"(format: lasercell.cell
version: 1
frames: [camera, sensor, vision_base, vision_flange]
robots:
  vision_robot:
    model: dh
    convention: standard
    base_from_chain: {translation_mm: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}
    chain_from_flange: {translation_mm: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}
    joints:
      - {a_mm: 0, alpha_rad: 1.5707963267948966, d_mm: 89.159, theta_offset_rad: 0, joint_offset_rad: 0}
      - {a_mm: -425, alpha_rad: 0, d_mm: 0, theta_offset_rad: 0, joint_offset_rad: 0}
      - {a_mm: -392.25, alpha_rad: 0, d_mm: 0, theta_offset_rad: 0, joint_offset_rad: 0}
      - {a_mm: 0, alpha_rad: 1.5707963267948966, d_mm: 109.15, theta_offset_rad: 0, joint_offset_rad: 0}
      - {a_mm: 0, alpha_rad: -1.5707963267948966, d_mm: 94.65, theta_offset_rad: 0, joint_offset_rad: 0}
      - {a_mm: 0, alpha_rad: 0, d_mm: 82.3, theta_offset_rad: 0, joint_offset_rad: 0}
edges:
  - parent: vision_flange
    child: sensor
    type: static
    parent_from_child: {translation_mm: [1.5, -2, 300], rotation_wxyz: [1, 0, 0, 0]}
    provenance: {tool: "lasercell calibrate handeye 0.1.0", date: "2026-11-26T10:00:00Z", input_digest: "sha256:ab", residual_summary: "rms \"0.021\" mm \\ 4 spheres"}
  - parent: sensor
    child: camera
    type: static
    parent_from_child: {translation_mm: [0, 0, 25], rotation_wxyz: [0, 1, 0, 0]}
    covariance: [0.25, 0, 0, 0.5, 0, 0,
                 0, 0.25, 0, 0, 0, 0,
                 0, 0, 0.25, 0, 0, 0,
                 0.5, 0, 0, 4, 0, 0,
                 0, 0, 0, 0, 4, 0,
                 0, 0, 0, 0, 0, 4]
    provenance: {tool: "", date: "", input_digest: "", residual_summary: ""}
  - parent: vision_base
    child: vision_flange
    type: dynamic
    robot: vision_robot
)";

/// A random cell: a tree of static edges with covariances and awkward provenance strings, two
/// robots (standard and modified DH, mounting transforms) driving two dynamic edges.
FrameGraph RandomCell(std::mt19937& rng, int frames) {
  std::normal_distribution<double> n(0.0, 1.0);
  const std::vector<std::string> texts = {"lasercell calibrate spheres 0.1.0",
                                          "a \"quoted\" \\ text",
                                          "line\nbreak\ttab",
                                          "null",
                                          "- x: {y}",
                                          "# not a comment",
                                          "  padded  ",
                                          "µm ±0.02",
                                          ""};
  FrameGraph graph;
  for (const char* robot : {"vision_robot", "handling_robot"}) {
    std::vector<DhJoint> rows(6);
    for (DhJoint& r : rows) r = {300 * n(rng), 2 * n(rng), 300 * n(rng), n(rng), 1e-3 * n(rng)};
    const Eigen::Isometry3d base = RandomPose(rng);
    const Eigen::Isometry3d tool = RandomPose(rng);
    graph.SetRobot(
        robot, DhChain(robot[0] == 'v' ? DhConvention::kStandard : DhConvention::kModified, rows,
                       base, tool));
  }
  for (int i = 1; i < frames; ++i) {
    const int j = std::uniform_int_distribution<int>(0, i - 1)(rng);
    StaticEdge edge =
        Edge("frame_" + std::to_string(j), "frame_" + std::to_string(i), RandomPose(rng));
    if (i % 2 == 0) {
      Matrix6d a;
      for (int k = 0; k < 36; ++k) a(k / 6, k % 6) = 1e-3 * n(rng);
      edge.covariance = a * a.transpose();
    }
    edge.provenance = {texts[i % texts.size()], texts[(i + 1) % texts.size()],
                       "sha256:" + std::to_string(i), texts[(i + 3) % texts.size()]};
    graph.SetStaticEdge(edge);
  }
  graph.SetDynamicEdge({"frame_0", "vision_flange", "vision_robot"});
  graph.SetDynamicEdge({"handling_base", "frame_1", "handling_robot"});
  return graph;
}

void ExpectIdentical(const FrameGraph& a, const FrameGraph& b) {
  EXPECT_EQ(a.Frames(), b.Frames());
  ASSERT_EQ(a.static_edges().size(), b.static_edges().size());
  for (std::size_t i = 0; i < a.static_edges().size(); ++i) {
    const StaticEdge &x = a.static_edges()[i], &y = b.static_edges()[i];
    EXPECT_EQ(x.parent, y.parent);
    EXPECT_EQ(x.child, y.child);
    EXPECT_TRUE(SamePose(x.parent_from_child, y.parent_from_child)) << "edge " << i;
    EXPECT_EQ(x.ParentFromChild().matrix(), y.ParentFromChild().matrix()) << "edge " << i;
    ASSERT_EQ(x.covariance.has_value(), y.covariance.has_value());
    if (x.covariance) {
      EXPECT_EQ(*x.covariance, *y.covariance);
    }
    EXPECT_EQ(x.provenance.tool, y.provenance.tool);
    EXPECT_EQ(x.provenance.date, y.provenance.date);
    EXPECT_EQ(x.provenance.input_digest, y.provenance.input_digest);
    EXPECT_EQ(x.provenance.residual_summary, y.provenance.residual_summary);
  }
  ASSERT_EQ(a.dynamic_edges().size(), b.dynamic_edges().size());
  for (std::size_t i = 0; i < a.dynamic_edges().size(); ++i) {
    EXPECT_EQ(a.dynamic_edges()[i].parent, b.dynamic_edges()[i].parent);
    EXPECT_EQ(a.dynamic_edges()[i].child, b.dynamic_edges()[i].child);
    EXPECT_EQ(a.dynamic_edges()[i].robot, b.dynamic_edges()[i].robot);
  }
  ASSERT_EQ(a.Robots(), b.Robots());
  for (const std::string& robot : a.Robots()) {
    const auto& x = dynamic_cast<const DhChain&>(a.Robot(robot));
    const auto& y = dynamic_cast<const DhChain&>(b.Robot(robot));
    EXPECT_EQ(x.convention(), y.convention());
    EXPECT_TRUE(SamePose(x.base_from_chain_stored(), y.base_from_chain_stored()));
    EXPECT_TRUE(SamePose(x.chain_from_flange_stored(), y.chain_from_flange_stored()));
    EXPECT_TRUE(SameBits(x.base_from_chain().matrix(), y.base_from_chain().matrix()));
    EXPECT_TRUE(SameBits(x.chain_from_flange().matrix(), y.chain_from_flange().matrix()));
    ASSERT_EQ(x.joints().size(), y.joints().size());
    for (std::size_t j = 0; j < x.joints().size(); ++j) {
      EXPECT_EQ(x.joints()[j].a_mm, y.joints()[j].a_mm);
      EXPECT_EQ(x.joints()[j].alpha_rad, y.joints()[j].alpha_rad);
      EXPECT_EQ(x.joints()[j].d_mm, y.joints()[j].d_mm);
      EXPECT_EQ(x.joints()[j].theta_offset_rad, y.joints()[j].theta_offset_rad);
      EXPECT_EQ(x.joints()[j].joint_offset_rad, y.joints()[j].joint_offset_rad);
    }
  }
}

TEST(FrameGraphYamlTest, WritesTheDocumentedShape) {
  EXPECT_EQ(FrameGraphToYaml(ExampleCell()), kExampleText);
  EXPECT_EQ(FrameGraphToYaml(FrameGraph()),
            "format: lasercell.cell\nversion: 1\nframes: []\nrobots: {}\nedges: []\n");
  EXPECT_EQ(PoseToFileNotation(Eigen::Isometry3d(Eigen::Translation3d(1.5, -2, 300))),
            "{translation_mm: [1.5, -2, 300], rotation_wxyz: [1, 0, 0, 0]}");
  // Read back: same text, same doubles.
  const FrameGraph read = FrameGraphFromYaml(kExampleText, "cell.yaml");
  EXPECT_EQ(FrameGraphToYaml(read), kExampleText);
  ExpectIdentical(read, ExampleCell());
}

TEST(FrameGraphYamlTest, FormatDoubleIsShortestAndExact) {
  EXPECT_EQ(FormatDouble(0.1), "0.1");
  EXPECT_EQ(FormatDouble(-425.0), "-425");
  EXPECT_EQ(FormatDouble(std::numbers::pi / 2), "1.5707963267948966");
  EXPECT_EQ(FormatDouble(1e-6), "1e-06");
  EXPECT_EQ(FormatDouble(-0.0), "-0");
  std::mt19937_64 rng(17);
  for (int i = 0; i < 10000; ++i) {
    const std::uint64_t bits = rng();
    double value;
    std::memcpy(&value, &bits, sizeof value);
    if (!std::isfinite(value)) continue;
    const std::string text = FormatDouble(value);
    double back = 0;
    std::from_chars(text.data(), text.data() + text.size(), back);
    EXPECT_EQ(std::memcmp(&back, &value, sizeof value), 0) << text;
  }
}

TEST(FrameGraphYamlTest, RandomCellsRoundTripBitExactly) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  for (int trial = 0; trial < 20; ++trial) {
    const FrameGraph original = RandomCell(rng, 3 + trial);
    const std::string text1 = FrameGraphToYaml(original);
    const FrameGraph first = FrameGraphFromYaml(text1, "first.yaml");
    const std::string text2 = FrameGraphToYaml(first);
    ASSERT_EQ(text1, text2) << "trial " << trial;
    const FrameGraph second = FrameGraphFromYaml(text2, "second.yaml");
    ExpectIdentical(first, second);
    JointValues joints;
    for (const char* robot : {"vision_robot", "handling_robot"}) {
      for (int j = 0; j < 6; ++j) joints[robot].push_back(angle(rng));
    }
    const Eigen::Isometry3d t1 = first.Transform("vision_flange", "handling_base", joints);
    EXPECT_EQ(t1.matrix(), second.Transform("vision_flange", "handling_base", joints).matrix());
    // Against the original: everything exact, robots' mounts included (DhChain stores them as
    // the file does).
    ExpectIdentical(original, first);
    const Eigen::Isometry3d t0 = original.Transform("vision_flange", "handling_base", joints);
    EXPECT_EQ(t0.matrix(), t1.matrix());
    for (std::size_t i = 0; i < original.static_edges().size(); ++i) {
      const StaticEdge &o = original.static_edges()[i], &r = first.static_edges()[i];
      EXPECT_TRUE(SamePose(o.parent_from_child, r.parent_from_child))
          << "trial " << trial << " edge " << i;
      EXPECT_EQ(o.provenance.tool, r.provenance.tool);
      EXPECT_EQ(o.provenance.residual_summary, r.provenance.residual_summary);
      if (o.covariance) {
        EXPECT_EQ(*o.covariance, *r.covariance);
      }
    }
  }
}

/// A pose as calibrations make them: from a quaternion, from an angle-axis of any angle (tiny
/// and near pi included), or after arithmetic (slightly off orthonormal).
Eigen::Isometry3d AnyPose(std::mt19937& rng, int trial) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d t{n(rng), n(rng), n(rng)};
  if (trial % 3 == 0) {
    return PoseFromQuaternion(Eigen::Quaterniond{n(rng), n(rng), n(rng), n(rng)}, t);
  }
  if (trial % 3 == 1) {
    const Eigen::Vector2d e{n(rng), n(rng)};
    const double angle = trial % 2 ? std::numbers::pi - std::pow(10.0, -e.x() * e.y() - 1)
                                   : std::pow(10.0, -8 * std::abs(e.x()));
    return Eigen::Translation3d(t) * Eigen::AngleAxisd(angle, Draws<3>(n, rng).normalized());
  }
  const Eigen::Isometry3d a = RandomPose(rng);
  const Eigen::Isometry3d b = RandomPose(rng);
  return a * b * RandomPose(rng).inverse();
}

/// The rotation_wxyz numbers of the first pose in `text` after `field`.
Eigen::Vector4d WrittenWxyz(const std::string& text, const std::string& field) {
  const std::size_t at = text.find("rotation_wxyz: [", text.find(field)) + 16;
  std::istringstream in(text.substr(at));
  Eigen::Vector4d wxyz;
  char comma;
  in >> wxyz[0] >> comma >> wxyz[1] >> comma >> wxyz[2] >> comma >> wxyz[3];
  return wxyz;
}

TEST(FrameGraphYamlTest, EveryPoseRoundTripsBitExactly) {
  // A static edge stores the quaternion it writes, and reads back the very same doubles.
  std::mt19937 rng(8);
  for (int trial = 0; trial < 1200; ++trial) {
    const Eigen::Isometry3d pose = AnyPose(rng, trial);
    FrameGraph graph;
    graph.SetStaticEdge(Edge("a", "b", pose));
    const std::string text1 = FrameGraphToYaml(graph);
    const FrameGraph first = FrameGraphFromYaml(text1, "first.yaml");
    ASSERT_TRUE(SamePose(first.static_edges()[0].parent_from_child,
                         graph.static_edges()[0].parent_from_child))
        << "trial " << trial;
    const std::string text2 = FrameGraphToYaml(first);
    ASSERT_EQ(text1, text2) << "trial " << trial;
    const Eigen::Isometry3d read = first.static_edges()[0].ParentFromChild();
    EXPECT_EQ(read.translation(), pose.translation());
    EXPECT_LT((read.linear() - pose.linear()).cwiseAbs().maxCoeff(), 1e-14) << "trial " << trial;
    // The written quaternion is unit with w >= 0.
    const Eigen::Vector4d wxyz = WrittenWxyz(text1, "parent_from_child");
    EXPECT_GE(wxyz[0], 0.0);
    EXPECT_NEAR(wxyz.norm(), 1.0, 1e-15);
  }
}

TEST(FrameGraphYamlTest, RobotMountsRoundTripBitExactly) {
  // DhChain stores its mounting transforms as the file holds them (QuaternionPose): a matrix is
  // converted once, then write -> read -> write gives the same text and the same doubles.
  std::mt19937 rng(9);
  for (int trial = 0; trial < 600; ++trial) {
    const Eigen::Isometry3d base_from_chain = AnyPose(rng, trial);
    const Eigen::Isometry3d chain_from_flange = AnyPose(rng, trial + 1);
    FrameGraph graph;
    graph.SetRobot("arm", DhChain(DhConvention::kStandard, {{1, 0.5, 2, 0, 0}}, base_from_chain,
                                  chain_from_flange));
    const std::string text1 = FrameGraphToYaml(graph);
    const FrameGraph first = FrameGraphFromYaml(text1, "first.yaml");
    const std::string text2 = FrameGraphToYaml(first);
    ASSERT_EQ(text1, text2) << "trial " << trial;
    const FrameGraph second = FrameGraphFromYaml(text2, "second.yaml");
    ExpectIdentical(first, second);
    const auto& read = dynamic_cast<const DhChain&>(first.Robot("arm"));
    const auto& built = dynamic_cast<const DhChain&>(graph.Robot("arm"));
    EXPECT_TRUE(SamePose(read.base_from_chain_stored(), built.base_from_chain_stored()));
    EXPECT_TRUE(SamePose(read.chain_from_flange_stored(), built.chain_from_flange_stored()));
    EXPECT_EQ(read.base_from_chain().translation(), base_from_chain.translation());
    EXPECT_LT((read.base_from_chain().linear() - base_from_chain.linear()).cwiseAbs().maxCoeff(),
              1e-14);
    EXPECT_LT(
        (read.chain_from_flange().linear() - chain_from_flange.linear()).cwiseAbs().maxCoeff(),
        1e-14);
    for (const char* field : {"base_from_chain", "chain_from_flange"}) {
      const Eigen::Vector4d wxyz = WrittenWxyz(text1, field);
      EXPECT_GE(wxyz[0], 0.0);
      EXPECT_NEAR(wxyz.norm(), 1.0, 1e-15);
    }
  }
  // Copies and re-registered models keep that; a changed mount is written anew, from a matrix
  // with the canonical quaternion, from a QuaternionPose exactly as given.
  const FrameGraph read = FrameGraphFromYaml(
      FrameGraphToYaml([&] {
        FrameGraph g;
        g.SetRobot("arm", DhChain(DhConvention::kModified, {}, AnyPose(rng, 0), AnyPose(rng, 2)));
        return g;
      }()),
      "cell.yaml");
  const std::string text = FrameGraphToYaml(read);
  FrameGraph copy = read;
  copy.SetRobot("arm", DhChain(dynamic_cast<const DhChain&>(read.Robot("arm"))));
  EXPECT_EQ(FrameGraphToYaml(copy), text);
  DhChain moved = dynamic_cast<const DhChain&>(read.Robot("arm"));
  const Eigen::Isometry3d new_base(Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitZ()));
  moved.set_base_from_chain(new_base);
  copy.SetRobot("arm", moved);
  EXPECT_THAT(FrameGraphToYaml(copy),
              HasSubstr("base_from_chain: " + PoseToFileNotation(new_base)));
  const QuaternionPose new_flange{Eigen::Quaterniond(-0.6000000002, -0.0, 0.0, 0.8),
                                  Eigen::Vector3d(0.1, -0.0, 1e-300)};
  moved.set_chain_from_flange(new_flange);
  copy.SetRobot("arm", moved);
  const std::string flange_text =
      "chain_from_flange: {translation_mm: [0.1, -0, 1e-300], "
      "rotation_wxyz: [-0.6000000002, -0, 0, 0.8]}";
  EXPECT_THAT(FrameGraphToYaml(copy), HasSubstr(flange_text));
  const FrameGraph reread = FrameGraphFromYaml(FrameGraphToYaml(copy), "cell.yaml");
  EXPECT_TRUE(SamePose(dynamic_cast<const DhChain&>(reread.Robot("arm")).chain_from_flange_stored(),
                       new_flange));
}

TEST(FrameGraphYamlTest, ReplacingOneEdgeChangesOnlyItsLines) {
  std::mt19937 rng(4);
  const std::string before_text = FrameGraphToYaml(RandomCell(rng, 9));
  FrameGraph graph = FrameGraphFromYaml(before_text, "cell.yaml");
  StaticEdge edge = graph.static_edges()[3];
  edge.SetParentFromChild(RandomPose(rng));
  edge.provenance.tool = "lasercell calibrate handeye 0.2.0";
  graph.SetStaticEdge(edge);
  const std::string after_text = FrameGraphToYaml(graph);
  std::istringstream before(before_text), after(after_text);
  std::string b, a;
  std::vector<std::string> changed;
  while (std::getline(before, b) && std::getline(after, a)) {
    if (a != b) changed.push_back(a);
  }
  EXPECT_FALSE(std::getline(after, a));  // same number of lines
  ASSERT_EQ(changed.size(), 2u);
  EXPECT_THAT(changed[0], StartsWith("    parent_from_child: "));
  EXPECT_THAT(changed[1], HasSubstr("lasercell calibrate handeye 0.2.0"));
}

constexpr const char* kValid = R"(format: lasercell.cell
version: 1
frames: [a, b, c, d]
robots:
  arm:
    model: dh
    convention: standard
    joints:
      - {a_mm: 0, alpha_rad: 0, d_mm: 100}
edges:
  - parent: a
    child: b
    type: static
    parent_from_child: {translation_mm: [1, 2, 3], rotation_wxyz: [1, 0, 0, 0]}
  - parent: b
    child: c
    type: static
    parent_from_child: {translation_mm: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}
    covariance: [1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1]
    provenance: {tool: "t", date: "d"}
  - parent: c
    child: d
    type: dynamic
    robot: arm
)";

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "'" << from << "' not in the test text";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

/// what() of the FileError the reader throws for `text`, or "" (with a failure) when none.
std::string ReadError(const std::string& text) {
  try {
    FrameGraphFromYaml(text, "cells/bad.yaml");
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), "cells/bad.yaml");
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a FileError: " << e.what();
    return "";
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return "";
}

TEST(FrameGraphYamlTest, ValidMinimalFileReads) {
  const FrameGraph graph = FrameGraphFromYaml(kValid, "cell.yaml");
  EXPECT_EQ(graph.static_edges().size(), 2u);
  EXPECT_EQ(graph.static_edges()[1].provenance.tool, "t");
  EXPECT_EQ(graph.static_edges()[1].provenance.input_digest, "");
  const Eigen::Isometry3d a_from_d = graph.Transform("a", "d", {{"arm", {0.5}}});
  EXPECT_LT((a_from_d.translation() - Eigen::Vector3d(1, 2, 103)).norm(), 1e-12);
}

TEST(FrameGraphYamlTest, FileQuaternionsAreKeptAsWritten) {
  // Any sign, -0, and a norm off 1 by less than 1e-9: read as written, written as read; only
  // the matrices are built from the normalized quaternion.
  const std::string pose =
      "{translation_mm: [0.1, -0, 1e-300], rotation_wxyz: [-0.6000000002, -0, 0, 0.8]}";
  const std::string text = Replace(
      Replace(FrameGraphToYaml(ExampleCell()),
              "parent_from_child: {translation_mm: [1.5, -2, 300], rotation_wxyz: [1, 0, 0, 0]}",
              "parent_from_child: " + pose),
      "base_from_chain: {translation_mm: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}",
      "base_from_chain: " + pose);
  const FrameGraph graph = FrameGraphFromYaml(text, "cell.yaml");
  EXPECT_EQ(FrameGraphToYaml(graph), text);
  const StaticEdge& edge = graph.static_edges()[0];
  const Eigen::Quaterniond q(-0.6000000002, -0.0, 0.0, 0.8);
  const QuaternionPose as_written{q, Eigen::Vector3d(0.1, -0.0, 1e-300)};
  EXPECT_TRUE(SamePose(edge.parent_from_child, as_written));
  EXPECT_EQ(edge.ParentFromChild().matrix(),
            PoseFromQuaternion(q, as_written.translation_mm).matrix());
  const auto& robot = dynamic_cast<const DhChain&>(graph.Robot("vision_robot"));
  EXPECT_TRUE(SamePose(robot.base_from_chain_stored(), as_written));
  EXPECT_EQ(robot.base_from_chain().matrix(),
            PoseFromQuaternion(q, as_written.translation_mm).matrix());
}

TEST(FrameGraphYamlTest, BadFilesNameTheFileAndTheProblem) {
  const std::string v = kValid;
  const std::string cov35 =
      "[1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, "
      "0, 0, 0, 0, 1]";
  const std::string cov_asym =
      "[1, 0, 0, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, "
      "0, 0, 0, 0, 0, 0, 1]";
  const std::string cov36 =
      "[1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, "
      "0, 0, 0, 0, 0, 1]";
  const std::string fourth_edge =
      "  - parent: d\n    child: a\n    type: static\n    parent_from_child: "
      "{translation_mm: [0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}\n";
  const struct {
    std::string text;
    std::string problem;
  } cases[] = {
      {"- a\n- b\n", "is not a mapping at the top level"},
      {"", "is empty"},
      {Replace(v, "format: lasercell.cell\n", ""),
       "line 1: field 'format' is required, expected 'lasercell.cell'"},
      {Replace(v, "lasercell.cell", "lasercell.job"),
       "line 1: field 'format' is 'lasercell.job', expected 'lasercell.cell' (is this a "
       "lasercell cell file?)"},
      {Replace(v, "version: 1\n", ""),
       "field 'version' is required; this build reads lasercell.cell version 1"},
      {Replace(v, "version: 1", "version: 7"),
       "line 2: field 'version' is 7; this build reads lasercell.cell version 1"},
      {Replace(v, "version: 1", "version: one"),
       "line 2: field 'version' must be an integer (got 'one')"},
      {Replace(v, "frames: [a, b, c, d]", "frames: a"),
       "line 3: field 'frames' must be a list of names"},
      {Replace(v, "[a, b, c, d]", "[a, b, c, d, B]"), "'B' is not lower snake case"},
      {Replace(v, "[a, b, c, d]", "[a, b, c, d, a]"), "frame 'a' is listed twice"},
      {Replace(v, "child: b", "child: nowhere"),
       "line 12: field 'edges[0].child': frame 'nowhere' is not listed in frames"},
      {v + fourth_edge, "would create a cycle: d and a are already connected via d -> c"},
      {Replace(v, "    child: c\n", "    child: a\n"),
       "line 15: field 'edges[1]' would create a cycle: b and a are already joined by edges[0]"},
      {Replace(v, "rotation_wxyz: [1, 0, 0, 0]}", "rotation_wxyz: [1.2, 0, 0, 0]}"),
       "line 14: field 'edges[0].parent_from_child.rotation_wxyz' has norm 1.2; expected a unit "
       "quaternion"},
      {Replace(v, "[1, 2, 3]", "[1, 2]"),
       "line 14: field 'edges[0].parent_from_child.translation_mm' must list exactly 3 numbers "
       "(got 2)"},
      {Replace(v, "[1, 2, 3]", "[1, .nan, 3]"),
       "translation_mm[1]' must be a finite number (got '.nan')"},
      {Replace(v, "[1, 2, 3]", "[1, 2, 1e999]"), "must be a finite number (got '1e999')"},
      {Replace(v, "[1, 2, 3]", "[1, 2, inf]"), "must be a finite number (got 'inf')"},
      {Replace(v, "[1, 2, 3]", "[1, 2, 3mm]"), "must be a finite number (got '3mm')"},
      {Replace(v, cov36, cov35),
       "line 19: field 'edges[1].covariance' must list exactly 36 numbers (got 35)"},
      {Replace(v, cov36, cov_asym), "covariance is not symmetric"},
      {Replace(v, "type: static", "type: stat"),
       "line 13: field 'edges[0].type': unknown type 'stat'; expected static or dynamic"},
      {Replace(v, "robot: arm", "robot: ghost"),
       "line 24: field 'edges[2].robot': robot 'ghost' is not declared under robots"},
      {Replace(v, "model: dh", "model: urdf"),
       "line 6: field 'robots.arm.model': unknown model 'urdf'"},
      {Replace(v, "convention: standard", "convention: craig"),
       "field 'robots.arm.convention': unknown convention 'craig'"},
      {Replace(v, "    joints:\n", "    convention: modified\n    joints:\n"),
       "line 8: field 'robots.arm.convention' appears twice"},
      {Replace(v, "  - parent: b", "  - parnet: b"),
       "line 15: unknown field 'edges[1].parnet' (known fields here: parent, child, type"},
      {Replace(v, "edges:", "edgez:"),
       "line 10: unknown field 'edgez' (known fields here: format, version, frames"},
      {Replace(v, "d_mm: 100", "d_mmm: 100"), "line 9: unknown field 'robots.arm.joints[0].d_mmm'"},
      {Replace(v, "{tool:", "{tol:"), "line 20: unknown field 'edges[1].provenance.tol'"},
      {Replace(v, "rotation_wxyz: [1, 0, 0, 0]}\n  - parent: b",
               "rotation_xyzw: [1, 0, 0, 0]}\n  - parent: b"),
       "line 14: unknown field 'edges[0].parent_from_child.rotation_xyzw'"},
      {Replace(v, "    type: static\n", "    type: static\n    robot: arm\n"),
       "line 14: unknown field 'edges[0].robot' (known fields here: parent, child, type, "
       "parent_from_child, covariance, sensor_response, provenance)"},
      {Replace(v, "    type: dynamic\n", "    type: dynamic\n    covariance: [1]\n"),
       "line 24: unknown field 'edges[2].covariance' (known fields here: parent, child, type, "
       "robot)"},
      {Replace(v, "    robot: arm\n",
               "    robot: arm\n  - parent: a\n    child: x\n    type: dynamic\n    robot: arm\n"),
       "line 26: field 'edges[3].child': frame 'x' is not listed"},
      {Replace(Replace(v, "[a, b, c, d]", "[a, b, c, d, e]"), "    robot: arm\n",
               "    robot: arm\n  - parent: d\n    child: e\n    type: dynamic\n    robot: arm\n"),
       "line 28: field 'edges[3].robot': robot 'arm' already drives edges[2]"},
      {Replace(v,
               "    parent_from_child: {translation_mm: [1, 2, 3], rotation_wxyz: [1, 0, 0, 0]}\n",
               ""),
       "line 11: field 'edges[0].parent_from_child' is required"},
      {Replace(v, "frames: [a, b, c, d]", "frames: [a, b, c, d"), "YAML syntax error at line"},
  };
  for (const auto& c : cases) {
    EXPECT_THAT(ReadError(c.text), AllOf(StartsWith("cells/bad.yaml: "), HasSubstr(c.problem)))
        << "expected: " << c.problem;
  }
  // Messages carry the line of the offending field.
  EXPECT_THAT(ReadError(Replace(v, "  - parent: b", "  - parnet: b")),
              HasSubstr("cells/bad.yaml: line 15: "));
  EXPECT_THAT(ReadError(Replace(v, "version: 1", "version: 7")),
              HasSubstr("cells/bad.yaml: line 2: "));
}

class NoFileFormModel final : public KinematicModel {
 public:
  int NumJoints() const override { return 0; }
  Eigen::Isometry3d BaseFromFlange(std::span<const double>) const override {
    return Eigen::Isometry3d::Identity();
  }
  std::unique_ptr<KinematicModel> Clone() const override {
    return std::make_unique<NoFileFormModel>();
  }
  std::string TypeName() const override { return "urdf"; }
};

TEST(FrameGraphYamlTest, SaveAndLoadRoundTripThroughFiles) {
  const test::TestDir dir("fg");
  const std::string path = dir.File("cell.yaml");
  SaveFrameGraph(path, ExampleCell());
  EXPECT_EQ(io::ReadFileBytes(path), kExampleText);
  ExpectIdentical(LoadFrameGraph(path), ExampleCell());
  EXPECT_EQ(dir.Entries(), 1u);  // no temporary files left
  try {
    LoadFrameGraph(dir.File("missing.yaml"));
    FAIL() << "no exception";
  } catch (const FileError& e) {
    EXPECT_THAT(e.what(), HasSubstr("missing.yaml"));
  }
  io::WriteFileAtomically(path, Replace(kExampleText, "version: 1", "version: 2"));
  try {
    LoadFrameGraph(path);
    FAIL() << "no exception";
  } catch (const FileError& e) {
    EXPECT_THAT(e.what(), AllOf(StartsWith(path + ": "),
                                HasSubstr("field 'version' is 2; this build reads")));
  }
}

TEST(FrameGraphYamlTest, FailedSavesLeaveTheExistingFileUnchanged) {
  const test::TestDir dir("fg");
  const std::string path = dir.File("cell.yaml");
  const std::string original = "format: lasercell.cell\nversion: 1\nframes: [kept]\n";
  io::WriteFileAtomically(path, original);
  // (1) A folder that does not exist.
  const std::string elsewhere = dir.File("missing_folder/cell.yaml");
  try {
    SaveFrameGraph(elsewhere, ExampleCell());
    ADD_FAILURE() << "no exception";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), elsewhere);
    EXPECT_THAT(e.what(), HasSubstr("does not exist"));
  }
  EXPECT_FALSE(fs::exists(dir.File("missing_folder")));
  // (2) A graph that cannot be written (model without a file form, non-finite DH value): the
  // text is complete before the file is touched.
  FrameGraph custom = ExampleCell();
  custom.SetRobot("other_robot", NoFileFormModel());
  FrameGraph non_finite = ExampleCell();
  DhChain broken = NominalUr5();
  broken.mutable_joints()[2].d_mm = std::nan("");
  non_finite.SetRobot("vision_robot", broken);
  for (const auto& [graph, problem] :
       {std::pair{&custom, "model type 'urdf' has no cell-file form"},
        std::pair{&non_finite, "not finite"}}) {
    try {
      SaveFrameGraph(path, *graph);
      ADD_FAILURE() << "no exception for " << problem;
    } catch (const FileError& e) {
      EXPECT_THAT(e.what(), AllOf(StartsWith(path + ": "), HasSubstr(problem)));
    }
    EXPECT_EQ(io::ReadFileBytes(path), original);
  }
  // (3) The rename fails (the target is a folder): nothing changes, no temporary left behind.
  const std::string folder = dir.File("occupied");
  fs::create_directories(folder + "/inside");
  EXPECT_THROW(SaveFrameGraph(folder, ExampleCell()), FileError);
  EXPECT_TRUE(fs::is_directory(folder + "/inside"));
  EXPECT_EQ(io::ReadFileBytes(path), original);
  EXPECT_EQ(dir.Entries(), 2u);  // cell.yaml and occupied/
}

}  // namespace
}  // namespace lasercell

namespace lasercell {
namespace {

// ---- Optional laser_planes section -----------------------------------------------------------

FrameGraph CellWithLaserPlane(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  FrameGraph graph;
  StaticEdge edge;
  edge.parent = "vision_flange";
  edge.child = "sensor";
  edge.SetParentFromChild(Eigen::Translation3d(12, -95, 160) *
                          Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  graph.SetStaticEdge(edge);
  LaserPlaneEntry plane;
  plane.normal = Draws<3>(g, rng).normalized();
  plane.point_mm = Draws<3>(g, rng) * 300.0;
  Eigen::Matrix4d a = Eigen::Matrix4d::NullaryExpr([&]() { return g(rng) * 1e-4; });
  plane.covariance = (a * a.transpose()).eval();
  plane.camera_covariance = (0.5 * a * a.transpose()).eval();
  plane.provenance = {"lasercell calibrate laser 0.1.0", "2026-11-26T06:00:00Z", "fnv1a64:0123",
                      "heights: rms 0.002 mm"};
  graph.SetLaserPlane("laser", plane);
  return graph;
}

TEST(FrameGraphYamlLaserPlanes, RoundTripIsBitExact) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const FrameGraph original = CellWithLaserPlane(rng);
    const std::string text1 = FrameGraphToYaml(original);
    const FrameGraph read = FrameGraphFromYaml(text1, "cell.yaml");
    EXPECT_EQ(FrameGraphToYaml(read), text1);
    const LaserPlaneEntry& a = original.laser_planes().at("laser");
    const LaserPlaneEntry& b = read.laser_planes().at("laser");
    EXPECT_EQ(a.normal, b.normal);  // bit-exact
    EXPECT_EQ(a.point_mm, b.point_mm);
    EXPECT_EQ(*a.covariance, *b.covariance);
    ASSERT_TRUE(b.camera_covariance.has_value());
    EXPECT_EQ(*a.camera_covariance, *b.camera_covariance);
    EXPECT_EQ(b.frame, "sensor");
    EXPECT_EQ(b.provenance.residual_summary, "heights: rms 0.002 mm");
  }
}

TEST(FrameGraphYamlLaserPlanes, SectionIsVersionedAndOmittedWhenEmpty) {
  std::mt19937 rng(6);
  const std::string text = FrameGraphToYaml(CellWithLaserPlane(rng));
  EXPECT_THAT(
      text, HasSubstr("laser_planes:\n  version: 1\n  planes:\n    laser:\n      frame: sensor\n"));
  FrameGraph empty;
  empty.AddFrame("sensor");
  EXPECT_THAT(FrameGraphToYaml(empty), Not(HasSubstr("laser_planes")));
}

TEST(FrameGraphYamlLaserPlanes, SettingThePlaneLeavesTheRestOfTheFileUnchanged) {
  std::mt19937 rng(7);
  FrameGraph graph = CellWithLaserPlane(rng);
  graph.RemoveLaserPlane("laser");
  const std::string before = FrameGraphToYaml(graph);
  graph.SetLaserPlane("laser", CellWithLaserPlane(rng).laser_planes().at("laser"));
  const std::string after = FrameGraphToYaml(graph);
  EXPECT_EQ(after.substr(0, before.size()), before);
}

TEST(FrameGraphYamlLaserPlanes, BadSectionsNameTheProblem) {
  std::mt19937 rng(8);
  const std::string v = FrameGraphToYaml(CellWithLaserPlane(rng));
  const auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = v;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  const struct {
    std::string text;
    std::string problem;
  } cases[] = {
      {replace("  version: 1\n  planes:", "  version: 2\n  planes:"),
       "line 12: field 'laser_planes.version' is 2; this build reads laser_planes version 1"},
      {replace("      frame: sensor\n", "      frame: sensor\n      colour: green\n"),
       "line 16: unknown field 'laser_planes.planes.laser.colour'"},
      {replace("      frame: sensor\n", "      frame: nowhere\n"),
       "frame 'nowhere' is not listed in frames"},
      {replace("      normal: [", "      normal: [2, "),
       "field 'laser_planes.planes.laser.normal' must list exactly 3 numbers"},
      {replace("  planes:\n", "  extra: 1\n  planes:\n"),
       "line 13: unknown field 'laser_planes.extra'"},
  };
  for (const auto& c : cases) {
    try {
      FrameGraphFromYaml(c.text, "cell.yaml");
      ADD_FAILURE() << "accepted: " << c.problem;
    } catch (const FileError& e) {
      EXPECT_THAT(e.what(), AllOf(StartsWith("cell.yaml: "), HasSubstr(c.problem)));
    }
  }
  // A non-unit normal.
  std::string s = v;
  const auto at = s.find("      normal: [");
  const auto end = s.find(']', at);
  s.replace(at, end - at + 1, "      normal: [0, 2, 0]");
  EXPECT_THROW(FrameGraphFromYaml(s, "cell.yaml"), FileError);
}

TEST(FrameGraphLaserPlanes, SetLaserPlaneChecksItsInput) {
  FrameGraph graph;
  LaserPlaneEntry plane;
  plane.normal = Eigen::Vector3d(0, 2, 0);
  EXPECT_THROW(graph.SetLaserPlane("laser", plane), InputError);
  plane.normal = Eigen::Vector3d::UnitY();
  EXPECT_THROW(graph.SetLaserPlane("Laser", plane), InputError);
  graph.SetLaserPlane("laser", plane);
  EXPECT_TRUE(graph.HasFrame("sensor"));
  EXPECT_DOUBLE_EQ(graph.laser_planes().at("laser").OffsetMm(), 0.0);
  const FrameGraph copy = graph;
  EXPECT_EQ(copy.laser_planes().size(), 1u);
  // The camera's part of the covariance needs the covariance it is part of.
  plane.camera_covariance = Eigen::Matrix4d::Identity() * 1e-8;
  try {
    graph.SetLaserPlane("laser", plane);
    FAIL() << "accepted camera_covariance without covariance";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("camera_covariance is the camera's part of covariance"));
  }
  plane.covariance = Eigen::Matrix4d::Identity() * 1e-8;
  (*plane.camera_covariance)(0, 1) = 1e-3;
  EXPECT_THROW(graph.SetLaserPlane("laser", plane), InputError);
}

}  // namespace
}  // namespace lasercell
