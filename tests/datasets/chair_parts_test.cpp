#include "datasets/chair_parts.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "datasets/part_rest.hpp"
#include "datasets/rng.hpp"
#include "localize/cad_import.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::datasets {
namespace {

constexpr double kPi = std::numbers::pi;
using Polygon = std::vector<Eigen::Vector3d>;
using localize::CadPrimitive;

// Sutherland-Hodgman: the part of a convex planar polygon with n . p <= c.
Polygon ClipByHalfSpace(const Polygon& poly, const Eigen::Vector3d& n, double c) {
  Polygon out;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector3d& a = poly[i];
    const Eigen::Vector3d& b = poly[(i + 1) % poly.size()];
    const double da = n.dot(a) - c, db = n.dot(b) - c;
    if (da <= 0) out.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

double PolygonArea(const Polygon& poly) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < poly.size(); ++i) sum += poly[i].cross(poly[(i + 1) % poly.size()]);
  return 0.5 * sum.norm();
}

// A face of a box primitive, as a polygon in the part frame, with its outward normal.
struct Face {
  Polygon corners;
  Eigen::Vector3d normal;
};

std::vector<Face> BoxFaces(const CadPrimitive& box) {
  std::vector<Face> faces;
  const Eigen::Vector3d& s = box.size_mm;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (double side : {0.0, 1.0}) {
      Face f;
      for (const auto& [a, b] : {std::pair{0, 0}, {1, 0}, {1, 1}, {0, 1}}) {
        Eigen::Vector3d q = Eigen::Vector3d::Zero();
        q[axis] = side * s[axis];
        q[u] = a * s[u];
        q[v] = b * s[v];
        f.corners.push_back(box.part_from_primitive * q);
      }
      f.normal = (side > 0 ? 1.0 : -1.0) * box.part_from_primitive.linear().col(axis);
      faces.push_back(f);
    }
  }
  return faces;
}

// The part of a polygon inside a box primitive (its six half-spaces in the part frame).
Polygon ClipByBox(Polygon poly, const CadPrimitive& box) {
  const Eigen::Matrix3d r = box.part_from_primitive.linear();
  const Eigen::Vector3d t = box.part_from_primitive.translation();
  for (int axis = 0; axis < 3 && !poly.empty(); ++axis) {
    const Eigen::Vector3d n = r.col(axis);
    poly = ClipByHalfSpace(poly, -n, -n.dot(t));                    // q_axis >= 0
    poly = ClipByHalfSpace(poly, n, n.dot(t) + box.size_mm[axis]);  // q_axis <= size
  }
  return poly;
}

// True when `face` lies in a face plane of `box` with the same outward normal.
bool CoplanarWithAFaceOf(const Face& face, const CadPrimitive& box) {
  for (const Face& g : BoxFaces(box)) {
    if (face.normal.dot(g.normal) > 1 - 1e-12 &&
        std::abs(g.normal.dot(face.corners[0] - g.corners[0])) < 1e-9) {
      return true;
    }
  }
  return false;
}

// Exposed area of the union of the solid's boxes: each face less its parts inside the other
// boxes (valid when no face point lies inside two others). Where two faces share a plane and
// side, the overlap is surface once: the earlier box keeps it.
double BoxUnionArea(const localize::CadSolid& solid) {
  double area = 0;
  for (std::size_t i = 0; i < solid.primitives.size(); ++i) {
    const CadPrimitive& a = solid.primitives[i];
    if (a.kind != CadPrimitive::kBox || a.subtract) continue;
    for (const Face& face : BoxFaces(a)) {
      area += PolygonArea(face.corners);
      for (std::size_t j = 0; j < solid.primitives.size(); ++j) {
        const CadPrimitive& b = solid.primitives[j];
        if (j == i || b.kind != CadPrimitive::kBox || b.subtract) continue;
        if (j > i && CoplanarWithAFaceOf(face, b)) continue;
        area -= PolygonArea(ClipByBox(face.corners, b));
      }
    }
  }
  return area;
}

// Bounding box of the additive primitives (boxes: corners; cylinders: their end circles).
Eigen::AlignedBox3d PrimitivesBox(const localize::CadSolid& solid) {
  Eigen::AlignedBox3d box;
  for (const CadPrimitive& p : solid.primitives) {
    if (p.subtract) continue;
    if (p.kind == CadPrimitive::kBox) {
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d c((k & 1) * p.size_mm.x(), ((k >> 1) & 1) * p.size_mm.y(),
                                ((k >> 2) & 1) * p.size_mm.z());
        box.extend(p.part_from_primitive * c);
      }
    } else {
      const Eigen::Vector3d a = p.part_from_primitive.linear().col(2);
      const Eigen::Vector3d reach =
          p.size_mm.x() * (Eigen::Vector3d::Ones() - a.cwiseAbs2()).cwiseSqrt();
      for (double h : {0.0, p.size_mm.y()}) {
        const Eigen::Vector3d c = p.part_from_primitive * Eigen::Vector3d(0, 0, h);
        box.extend(c + reach);
        box.extend(c - reach);
      }
    }
  }
  return box;
}

struct ReadBack {
  localize::CadModel model;
  Eigen::AlignedBox3d mesh_box;
};

ReadBack WriteAndRead(const CadChairPart& part, const test::TestDir& dir) {
  const std::string path = dir.File(part.name + ".step");
  localize::WriteCadSolid(path, part.solid, "mm");
  localize::CadImportOptions options;
  options.sampling_step_mm = 4.0;  // the samples are not checked here
  ReadBack r{localize::ReadCadModel(path, options), {}};
  for (const Eigen::Vector3d& p : r.model.mesh.vertices.positions) r.mesh_box.extend(p);
  return r;
}

TEST(ChairParts, SeatBackStepReadsBackWithTheAnalyticAreaAndBox) {
  const test::TestDir dir("chair_back");
  const SeatBackOptions o;
  const CadChairPart back = MakeSeatBack(o);
  const ReadBack r = WriteAndRead(back, dir);
  EXPECT_EQ(r.model.format, "step");
  EXPECT_EQ(r.model.solids, 1u);
  // Boxes (panel, wings, ridge) as clipped polygons; each boss adds its side wall and its hole's
  // wall (its top annulus and the hole's bottom together replace the disc it covers).
  double expected = BoxUnionArea(back.solid);
  expected += 2 * kPi *
              (o.grip_boss_radius_mm * o.grip_boss_height_mm +
               o.grip_hole_diameter_mm / 2 * o.grip_hole_depth_mm);
  expected += 2 * kPi *
              (o.mount_boss_radius_mm * o.mount_boss_height_mm +
               o.mount_hole_diameter_mm / 2 * o.mount_hole_depth_mm);
  EXPECT_NEAR(r.model.surface_area_mm2, expected, 1e-6 * expected);
  const Eigen::AlignedBox3d box = PrimitivesBox(back.solid);
  EXPECT_LT((r.mesh_box.min() - box.min()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((r.mesh_box.max() - box.max()).cwiseAbs().maxCoeff(), 1e-6);
  // The seed's scale (200-450 mm) and not flat.
  const Eigen::Vector3d size = box.sizes();
  EXPECT_GT(size.x(), 350);
  EXPECT_LT(size.x(), 450);
  EXPECT_GT(size.z(), 60);
  RecordProperty("back_area_mm2", std::to_string(r.model.surface_area_mm2));
  RecordProperty("back_size_mm", std::to_string(size.x()) + " x " + std::to_string(size.y()) +
                                     " x " + std::to_string(size.z()));
}

TEST(ChairParts, ArmrestStepReadsBackWithTheAnalyticAreaAndBox) {
  const test::TestDir dir("chair_armrest");
  const ArmrestOptions o;
  const CadChairPart arm = MakeArmrest(o);
  const ReadBack r = WriteAndRead(arm, dir);
  EXPECT_EQ(r.model.solids, 1u);
  // Boxes (post, bar, pad); the boss adds its side and loses the hole's disc on top, the hole
  // adds its wall through boss and post and its disc on the post's inner face.
  const double rh = o.hole_diameter_mm / 2;
  const double through = o.bar_width_y_mm - 2 * o.post_inset_mm + o.boss_height_mm;
  const double expected = BoxUnionArea(arm.solid) + 2 * kPi * o.boss_radius_mm * o.boss_height_mm +
                          2 * kPi * rh * through - 2 * kPi * rh * rh;
  EXPECT_NEAR(r.model.surface_area_mm2, expected, 1e-6 * expected);
  const Eigen::AlignedBox3d box = PrimitivesBox(arm.solid);
  EXPECT_LT((r.mesh_box.min() - box.min()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((r.mesh_box.max() - box.max()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_GT(box.sizes().maxCoeff(), 200);
  EXPECT_GT(box.sizes().minCoeff(), 50);
  RecordProperty("armrest_area_mm2", std::to_string(r.model.surface_area_mm2));
}

// The grasp frame sits in its hole: the axis runs through empty space for the hole's depth and
// on above the opening (the gripper's approach along -z is clear), the wall around it is
// material, and the frame is a rotation.
void ExpectGraspInItsHole(const CadChairPart& part) {
  ASSERT_FALSE(part.grasps.empty());
  for (const PartGrasp& g : part.grasps) {
    SCOPED_TRACE(part.name + "/" + g.name);
    const Eigen::Matrix3d r = g.part_from_grasp.linear();
    EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    const double radius = g.hole_diameter_mm / 2;
    for (double depth = -150; depth <= g.hole_depth_mm - 0.5; depth += 0.5) {
      EXPECT_FALSE(SolidContains(part.solid, g.part_from_grasp * Eigen::Vector3d(0, 0, -depth)))
          << "axis at depth " << depth;
      // Just inside the hole's radius: empty; just outside it, down the hole: the wall.
      for (double a = 0; a < 2 * kPi; a += kPi / 8) {
        const Eigen::Vector3d u(std::cos(a), std::sin(a), 0);
        const Eigen::Vector3d in = (radius - 0.2) * u + Eigen::Vector3d(0, 0, -depth);
        EXPECT_FALSE(SolidContains(part.solid, g.part_from_grasp * in));
        if (depth > 0.5) {
          const Eigen::Vector3d wall = (radius + 0.2) * u + Eigen::Vector3d(0, 0, -depth);
          EXPECT_TRUE(SolidContains(part.solid, g.part_from_grasp * wall)) << depth << " " << a;
        }
      }
    }
  }
}

TEST(ChairParts, GraspFramesSitInTheirHoles) {
  ExpectGraspInItsHole(MakeSeatBack());
  ExpectGraspInItsHole(MakeArmrest());
  // The back's hole is blind: material just below its bottom.
  const CadChairPart back = MakeSeatBack();
  const PartGrasp& g = back.grasps.front();
  EXPECT_TRUE(
      SolidContains(back.solid, g.part_from_grasp * Eigen::Vector3d(0, 0, -g.hole_depth_mm - 0.5)));
  EXPECT_EQ(g.hole_diameter_mm, 27.0);
}

TEST(ChairParts, RenderMeshIsClosedOutwardAndHoldsTheSolidsVolume) {
  const test::TestDir dir("chair_render");
  for (const CadChairPart& part : {MakeSeatBack(), MakeArmrest()}) {
    SCOPED_TRACE(part.name);
    const std::string path = dir.File(part.name + ".step");
    localize::WriteCadSolid(path, part.solid, "mm");
    const MeshPart mesh = ReadCadRenderMesh(path, 0.02);
    const MeshSolidCheck check = CheckMeshSolid(mesh.mesh);
    EXPECT_EQ(check.boundary_edges, 0u);
    EXPECT_EQ(check.inconsistent_edges, 0u);
    // Monte-Carlo volume of the constructive solid in its bounding box (seeded): the mesh's
    // enclosed volume agrees within 4 standard errors.
    const Eigen::AlignedBox3d box = PrimitivesBox(part.solid);
    Rng rng(StreamSeed(7, 1));
    const int n = 200000;
    int inside = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p{rng.Uniform(box.min().x(), box.max().x()),
                              rng.Uniform(box.min().y(), box.max().y()),
                              rng.Uniform(box.min().z(), box.max().z())};
      inside += SolidContains(part.solid, p) ? 1 : 0;
    }
    const double f = static_cast<double>(inside) / n;
    const double box_volume = box.volume();
    const double sigma = box_volume * std::sqrt(f * (1 - f) / n);
    EXPECT_NEAR(check.volume_mm3, f * box_volume, 4 * sigma);
    EXPECT_TRUE(box.contains(check.center_of_mass));
    RecordProperty(part.name + "_volume_mm3", std::to_string(check.volume_mm3));
    RecordProperty(part.name + "_triangles", std::to_string(mesh.mesh.faces.size()));
  }
}

TEST(ChairParts, OptionErrorsNameTheField) {
  const auto message = [](const auto& make) {
    try {
      make();
    } catch (const OptionError& e) {
      return std::string(e.what());
    }
    return std::string("no OptionError");
  };
  SeatBackOptions back;
  back.right_wing_angle_deg = 75;
  EXPECT_NE(message([&] { MakeSeatBack(back); }).find("SeatBackOptions.right_wing_angle_deg"),
            std::string::npos);
  back = {};
  back.grip_hole_diameter_mm = 46;
  EXPECT_NE(message([&] { MakeSeatBack(back); }).find("grip_hole_diameter_mm"), std::string::npos);
  back = {};
  back.mount_boss_xy_mm = {-50, 85};
  EXPECT_NE(message([&] { MakeSeatBack(back); }).find("overlap"), std::string::npos);
  ArmrestOptions arm;
  arm.boss_radius_mm = 30;
  EXPECT_NE(message([&] { MakeArmrest(arm); }).find("ArmrestOptions.boss_radius_mm"),
            std::string::npos);
  arm = {};
  arm.bar_thickness_mm = -1;
  EXPECT_NE(message([&] { MakeArmrest(arm); }).find("ArmrestOptions.bar_thickness_mm"),
            std::string::npos);
}

}  // namespace
}  // namespace lasercell::datasets
