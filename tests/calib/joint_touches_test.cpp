// Known sphere centres for the robot-side calibrations from the handling robot's touches
// (calib/robot_in_cell.hpp): one parser (ParseTouchesYaml) and one "up", +z of handling_base.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "calib/half_sphere_calibration.hpp"
#include "calib/robot_in_cell.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"

namespace lasercell::calib {
namespace {

using ::testing::HasSubstr;

StaticEdge Edge(const std::string& parent, const std::string& child, const Eigen::Isometry3d& t) {
  StaticEdge e;
  e.parent = parent;
  e.child = child;
  e.SetParentFromChild(t);
  return e;
}

// A cell whose `cell` frame is tilted by 8 deg against handling_base (the handling robot
// stands level, the cell's reference was drawn on a sloping wall): the two "up"s differ.
FrameGraph TiltedCell() {
  FrameGraph g;
  Eigen::Isometry3d cell_from_hb = Eigen::Isometry3d::Identity();
  cell_from_hb.linear() = Eigen::AngleAxisd(8.0 * M_PI / 180, Eigen::Vector3d::UnitX()).matrix();
  cell_from_hb.translation() = Eigen::Vector3d(900, -200, 50);
  Eigen::Isometry3d cell_from_vb = Eigen::Isometry3d::Identity();
  cell_from_vb.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).matrix();
  cell_from_vb.translation() = Eigen::Vector3d(-300, 400, 0);
  g.SetStaticEdge(Edge("cell", "handling_base", cell_from_hb));
  g.SetStaticEdge(Edge("cell", "vision_base", cell_from_vb));
  return g;
}

const char* kTouches =
    "format: lasercell.touches\nversion: 1\nrobot: handling_robot\nframe: handling_base\n"
    "stated_sigma_mm: 0.04\nsphere_radius_mm: 25\ntouches:\n"
    "  - {sphere: 1, point_in_handling_base: [100, 200, 325], joints_rad: null}\n"
    "  - {sphere: 0, point_in_handling_base: [-50, 250, 330], joints_rad: null}\n";

TEST(JointTouches, CentreIsTheTopMinusRadiusAlongHandlingBaseZ) {
  const FrameGraph g = TiltedCell();
  const SphereTouches t = ParseTouchesYaml(kTouches, "touches.yaml");
  const KnownSphereCentres k = CentresFromTouches(t, "touches.yaml", g, "vision_base");
  ASSERT_EQ(k.centres_in_base.size(), 2u);
  EXPECT_EQ(k.radius_mm, 25);
  EXPECT_EQ(k.sigma_mm, 0.04);
  const Eigen::Isometry3d vb_from_hb = g.Transform("vision_base", "handling_base");
  const Eigen::Vector3d want1 = vb_from_hb * Eigen::Vector3d(100, 200, 300);
  const Eigen::Vector3d want0 = vb_from_hb * Eigen::Vector3d(-50, 250, 305);
  EXPECT_LT((k.centres_in_base[1] - want1).norm(), 1e-9);
  EXPECT_LT((k.centres_in_base[0] - want0).norm(), 1e-9);
  // The rule the tool had (up = the cell's +z) puts the centre 25 * 2 sin(4 deg) = 3.5 mm away.
  const Eigen::Vector3d cell_up_in_hb = g.Transform("handling_base", "cell").linear().col(2);
  const Eigen::Vector3d wrong1 = vb_from_hb * (Eigen::Vector3d(100, 200, 325) - 25 * cell_up_in_hb);
  EXPECT_GT((k.centres_in_base[1] - wrong1).norm(), 3.0);
}

TEST(JointTouches, StatedUpAndRadiusFallback) {
  const FrameGraph g = TiltedCell();
  SphereTouches t = ParseTouchesYaml(kTouches, "touches.yaml");
  t.sphere_radius_mm.reset();
  EXPECT_THAT([&] { CentresFromTouches(t, "touches.yaml", g, "vision_base"); },
              testing::ThrowsMessage<FileError>(HasSubstr("sphere_radius_mm")));
  const Eigen::Vector3d up(0, 0.1, 1);
  const KnownSphereCentres k = CentresFromTouches(t, "touches.yaml", g, "vision_base", 20, up);
  const Eigen::Vector3d want = g.Transform("vision_base", "handling_base") *
                               (Eigen::Vector3d(100, 200, 325) - 20 * up.normalized());
  EXPECT_LT((k.centres_in_base[1] - want).norm(), 1e-9);
}

TEST(JointTouches, LabelsAndFramesAreChecked) {
  const FrameGraph g = TiltedCell();
  SphereTouches t = ParseTouchesYaml(kTouches, "touches.yaml");
  EXPECT_THAT([&] { CentresFromTouches(t, "touches.yaml", g, "vision_flange"); },
              testing::ThrowsMessage<FileError>(HasSubstr("not connected to 'vision_flange'")));
  t.touches[0].sphere = 5;
  EXPECT_THAT([&] { CentresFromTouches(t, "touches.yaml", g, "vision_base"); },
              testing::ThrowsMessage<FileError>(HasSubstr("sphere index 5 out of range")));
}

}  // namespace
}  // namespace lasercell::calib
