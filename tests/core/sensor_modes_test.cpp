// The sensor's error modes on a laser plane and a calibrated edge's response to them: cell.yaml
// round trip, bad input, and the response moved along a path by TransformWithCovariance.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/pose_covariance.hpp"

namespace lasercell {
namespace {

using ::testing::HasSubstr;

LaserPlaneEntry PlaneWithModes(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  LaserPlaneEntry plane;
  plane.normal = Eigen::Vector3d(0.1, -0.9, 0.4).normalized();
  plane.point_mm = Eigen::Vector3d(0, 200, 150);
  Eigen::Matrix4d cov = Eigen::Matrix4d::Zero();
  for (int k = 0; k < 5; ++k) {
    SensorErrorMode m;
    if (k < 3) {
      for (int i = 0; i < 12; ++i) m.intrinsics_step.push_back(g(rng) * 1e-3);
    }
    m.plane_step = Eigen::Vector4d{g(rng), g(rng), g(rng), g(rng) * 100} * 1e-5;
    cov += m.plane_step * m.plane_step.transpose();
    plane.error_modes.push_back(m);
  }
  plane.covariance = cov;
  plane.provenance = {"lasercell calibrate laser 0.1.0", "2026-12-04T06:00:00Z", "fnv1a64:abcd",
                      "heights"};
  return plane;
}

StaticEdge EdgeWithResponse(std::mt19937& rng, Eigen::Index modes) {
  std::normal_distribution<double> g(0.0, 1.0);
  StaticEdge edge;
  edge.parent = "handling_base";
  edge.child = "sensor";
  edge.SetParentFromChild(Eigen::Translation3d(400, -50, 700) *
                          Eigen::AngleAxisd(2.5, Eigen::Vector3d(1, 0.2, 0).normalized()));
  edge.sensor_response = SensorModeResponse{"laser", "fnv1a64:abcd",
                                            Eigen::Matrix<double, 6, Eigen::Dynamic>::NullaryExpr(
                                                6, modes, [&]() { return g(rng) * 1e-4; })};
  return edge;
}

TEST(SensorModes, CellFileRoundTripIsBitExact) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    FrameGraph graph;
    graph.SetLaserPlane("laser", PlaneWithModes(rng));
    graph.SetStaticEdge(EdgeWithResponse(rng, 5));
    const std::string text = FrameGraphToYaml(graph);
    const FrameGraph read = FrameGraphFromYaml(text, "cell.yaml");
    EXPECT_EQ(FrameGraphToYaml(read), text);
    const auto& a = graph.laser_planes().at("laser").error_modes;
    const auto& b = read.laser_planes().at("laser").error_modes;
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(a[k].intrinsics_step, b[k].intrinsics_step);
      EXPECT_EQ(a[k].plane_step, b[k].plane_step);
    }
    ASSERT_TRUE(read.static_edges()[0].sensor_response.has_value());
    const SensorModeResponse& r = *read.static_edges()[0].sensor_response;
    EXPECT_EQ(r.laser, "laser");
    EXPECT_EQ(r.plane_digest, "fnv1a64:abcd");
    EXPECT_EQ(r.columns, graph.static_edges()[0].sensor_response->columns);
  }
}

TEST(SensorModes, BadModesAndResponsesAreNamed) {
  std::mt19937 rng(12);
  FrameGraph graph;
  LaserPlaneEntry plane = PlaneWithModes(rng);
  plane.error_modes[1].intrinsics_step.pop_back();
  EXPECT_THROW(
      {
        try {
          graph.SetLaserPlane("laser", plane);
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), HasSubstr("error_modes[1] steps 11 intrinsics"));
          throw;
        }
      },
      InputError);
  plane = PlaneWithModes(rng);
  plane.error_modes[2].plane_step(3) = std::nan("");
  EXPECT_THROW(graph.SetLaserPlane("laser", plane), InputError);

  StaticEdge edge = EdgeWithResponse(rng, 3);
  edge.sensor_response->laser = "Laser plane";
  EXPECT_THROW(
      {
        try {
          graph.SetStaticEdge(edge);
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), HasSubstr("sensor_response.laser 'Laser plane'"));
          throw;
        }
      },
      InputError);

  // In the file: a column count that is not a multiple of 6 names the field and the line.
  FrameGraph ok;
  ok.SetLaserPlane("laser", PlaneWithModes(rng));
  ok.SetStaticEdge(EdgeWithResponse(rng, 2));
  std::string text = FrameGraphToYaml(ok);
  const std::size_t at = text.find("      columns: [") + 16;
  text.insert(at, "1, ");
  try {
    FrameGraphFromYaml(text, "cell.yaml");
    FAIL() << "accepted 13 response values";
  } catch (const FileError& e) {
    EXPECT_THAT(e.what(), HasSubstr("columns"));
    EXPECT_THAT(e.what(), HasSubstr("expected 6 per error mode"));
  }
}

// The response is moved into the query's `to` frame: compose the path by hand with the edge
// perturbed by +-h of a column and compare the left perturbation of the result.
TEST(SensorModes, TransformWithCovarianceMovesTheResponseAlongThePath) {
  std::mt19937 rng(13);
  FrameGraph graph;
  graph.SetStaticEdge(EdgeWithResponse(rng, 3));
  StaticEdge world;
  world.parent = "world";
  world.child = "handling_base";
  world.SetParentFromChild(Eigen::Translation3d(-1000, 300, 20) *
                           Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  graph.SetStaticEdge(world);
  StaticEdge part;
  part.parent = "part";
  part.child = "sensor";
  part.SetParentFromChild(Eigen::Translation3d(5, 6, 7) *
                          Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX()));
  graph.SetStaticEdge(part);
  const StaticEdge& e = graph.static_edges()[0];
  for (const auto& [to, from] : {std::pair<std::string, std::string>{"world", "sensor"},
                                 {"sensor", "world"},
                                 {"part", "world"}}) {
    const TransformWithCovarianceResult r = graph.TransformWithCovariance(to, from);
    ASSERT_EQ(r.sensor_responses.size(), 1u) << to << " <- " << from;
    for (Eigen::Index k = 0; k < 3; ++k) {
      const double h = 1e-3;
      Vector6d side[2];
      for (int s = 0; s < 2; ++s) {
        FrameGraph moved = graph;
        StaticEdge m = e;
        const Vector6d xi = (s == 0 ? h : -h) * e.sensor_response->columns.col(k);
        m.SetParentFromChild(ExpSe3(xi) * e.ParentFromChild());
        moved.SetStaticEdge(m);
        side[s] = LogSe3(moved.Transform(to, from) * r.to_from_from.inverse());
      }
      const Vector6d expected = (side[0] - side[1]) / (2 * h);
      EXPECT_LT((r.sensor_responses[0].columns.col(k) - expected).norm(),
                1e-6 * (1 + expected.norm()))
          << to << " <- " << from << " mode " << k;
    }
  }
}

}  // namespace
}  // namespace lasercell
