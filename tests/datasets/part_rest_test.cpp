#include "datasets/part_rest.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "datasets/geometry.hpp"

namespace lasercell::datasets {
namespace {

constexpr double kPi = std::numbers::pi;

// A box mesh (MakeBox gives each face its own corners; CheckMeshSolid welds them by position).
TriangleMesh BoxMesh(const Eigen::Vector3d& size, const Eigen::Vector3d& center) {
  return MakeBox(Eigen::Isometry3d(Eigen::Translation3d(center)), size).mesh;
}

TEST(PartRest, ABoxIsClosedOutwardWithItsVolumeAndCentre) {
  const TriangleMesh box = BoxMesh({40, 30, 20}, {5, -3, 12});
  const MeshSolidCheck c = CheckMeshSolid(box);
  EXPECT_TRUE(c.ClosedAndOutward());
  EXPECT_NEAR(c.volume_mm3, 40 * 30 * 20, 1e-9);
  EXPECT_LT((c.center_of_mass - Eigen::Vector3d(5, -3, 12)).norm(), 1e-12);
  // One triangle removed: its 3 edges are now used once.
  TriangleMesh open = box;
  open.faces.pop_back();
  EXPECT_EQ(CheckMeshSolid(open).boundary_edges, 3u);
  EXPECT_FALSE(CheckMeshSolid(open).ClosedAndOutward());
  // One triangle flipped: its edges are used twice in the same direction.
  TriangleMesh flipped = box;
  std::swap(flipped.faces[0][1], flipped.faces[0][2]);
  EXPECT_EQ(CheckMeshSolid(flipped).inconsistent_edges, 3u);
  // All flipped: closed but inward (negative volume).
  TriangleMesh inward = box;
  for (Eigen::Vector3i& f : inward.faces) std::swap(f[1], f[2]);
  const MeshSolidCheck in = CheckMeshSolid(inward);
  EXPECT_EQ(in.boundary_edges + in.inconsistent_edges, 0u);
  EXPECT_LT(in.volume_mm3, 0);
  EXPECT_FALSE(in.ClosedAndOutward());
}

TEST(PartRest, ATiltedBoxFallsOntoTheFaceBelowItsCentre) {
  // A 100 x 60 x 20 box tilted 30 deg about x and 10 deg about y: it must land flat on its
  // largest face (the one most nearly below it), the centre 10 mm above the plane.
  const TriangleMesh box = BoxMesh({100, 60, 20}, Eigen::Vector3d::Zero());
  const MeshSolidCheck c = CheckMeshSolid(box);
  const Eigen::Matrix3d start = (Eigen::AngleAxisd(0.5236, Eigen::Vector3d::UnitX()) *
                                 Eigen::AngleAxisd(0.1745, Eigen::Vector3d::UnitY()))
                                    .toRotationMatrix();
  const RestingPose rest = SettleOnPlane(box.vertices.positions, c.center_of_mass, start);
  const Eigen::Vector3d up = rest.plane_from_part.linear().row(2);
  EXPECT_NEAR(std::abs(up.z()), 1.0, 1e-9) << up.transpose();
  EXPECT_NEAR((rest.plane_from_part * c.center_of_mass).z(), 10.0, 1e-9);
  EXPECT_EQ(rest.contacts_in_part.size(), 4u);
  EXPECT_NEAR(rest.stability_margin_mm, 30.0, 1e-6);  // half the 60 mm side
  EXPECT_GE(rest.pivots, 1);
  // Already resting: no pivot, same pose.
  const RestingPose again =
      SettleOnPlane(box.vertices.positions, c.center_of_mass, rest.plane_from_part.linear());
  EXPECT_EQ(again.pivots, 0);
  EXPECT_TRUE(again.plane_from_part.isApprox(rest.plane_from_part, 1e-12));
}

TEST(PartRest, ALeaningTallBoxTipsOverOnlyBeyondItsTippingAngle) {
  // Balanced on an edge with the centre off to one side, a box lands on the face on that side.
  const TriangleMesh box = BoxMesh({20, 20, 80}, Eigen::Vector3d::Zero());
  const MeshSolidCheck c = CheckMeshSolid(box);
  const Eigen::Matrix3d start =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();  // leaning on +x
  const RestingPose rest = SettleOnPlane(box.vertices.positions, c.center_of_mass, start);
  // 0.3 rad from upright is beyond the 14 deg the 20 x 80 footprint allows: it lies down.
  const Eigen::Vector3d up = rest.plane_from_part.linear().row(2);
  EXPECT_LT(std::abs(up.z()), 1e-9);
  EXPECT_GT(rest.stability_margin_mm, 9.0);
  // A small lean stays upright.
  const RestingPose upright =
      SettleOnPlane(box.vertices.positions, c.center_of_mass,
                    Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix());
  EXPECT_NEAR(upright.plane_from_part.linear().row(2).z(), 1.0, 1e-9);
  EXPECT_THROW(
      SettleOnPlane({{0, 0, 0}, {1, 0, 0}}, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()),
      InputError);
  EXPECT_THROW(
      SettleOnPlane(box.vertices.positions, c.center_of_mass, Eigen::Matrix3d::Identity(), 0.0),
      InputError);
}

TEST(PartRest, HullsDistancesAndFootprintGaps) {
  const std::vector<Eigen::Vector2d> hull =
      ConvexHull2d({{0, 0}, {2, 0}, {1, 1}, {2, 2}, {0, 2}, {1, 0}, {0, 2}});
  ASSERT_EQ(hull.size(), 4u);  // the interior point and the collinear one dropped
  double area2 = 0;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
    area2 += a.x() * b.y() - a.y() * b.x();
  }
  EXPECT_NEAR(area2, 8.0, 1e-12);  // counter-clockwise: positive
  EXPECT_NEAR(SignedDistanceInside(hull, {1, 0.5}), 0.5, 1e-12);
  EXPECT_NEAR(SignedDistanceInside(hull, {3, 1}), -1.0, 1e-12);
  EXPECT_NEAR(SignedDistanceInside(hull, {3, 3}), -std::sqrt(2.0), 1e-12);
  const auto square = [](double x, double y) {
    return std::vector<Eigen::Vector2d>{{x, y}, {x + 1, y}, {x + 1, y + 1}, {x, y + 1}};
  };
  EXPECT_TRUE(ConvexPolygonsCloserThan(square(0, 0), square(0.5, 0.5), 0.0));  // overlap
  EXPECT_FALSE(ConvexPolygonsCloserThan(square(0, 0), square(1.5, 0), 0.4));   // 0.5 apart
  EXPECT_TRUE(ConvexPolygonsCloserThan(square(0, 0), square(1.5, 0), 0.6));
  // A square turned 45 deg with its corner 0.5 mm from the first square's side: apart, but the
  // edge-normal test may call it closer than 0.6 mm (conservative), never than 0.4 mm.
  std::vector<Eigen::Vector2d> diamond;
  for (int k = 0; k < 4; ++k) {
    const double a = k * kPi / 2;
    diamond.emplace_back(1.5 + std::sqrt(0.5) + std::cos(a) * std::sqrt(0.5),
                         0.5 + std::sin(a) * std::sqrt(0.5));
  }
  EXPECT_FALSE(ConvexPolygonsCloserThan(square(0, 0), ConvexHull2d(diamond), 0.4));
  EXPECT_TRUE(ConvexPolygonsCloserThan(square(0, 0), ConvexHull2d(diamond), 0.6));
}

}  // namespace
}  // namespace lasercell::datasets
