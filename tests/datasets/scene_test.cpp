#include "datasets/scene.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <map>
#include <numbers>
#include <thread>
#include <utility>

#include "core/se3.hpp"
#include "datasets/chair_seat.hpp"
#include "datasets/geometry.hpp"
#include "datasets/rng.hpp"

namespace lasercell::datasets {
namespace {

constexpr double kExactMm = 1e-6;

Eigen::Isometry3d Pose(double rx, double ry, double rz, double x, double y, double z) {
  return PoseFromRotationVector(Eigen::Vector3d(rx, ry, rz), Eigen::Vector3d(x, y, z));
}

// Random ray from around `from` aimed at a random point near `at`.
std::pair<Eigen::Vector3d, Eigen::Vector3d> RandomRay(Rng& rng, const Eigen::Vector3d& from,
                                                      const Eigen::Vector3d& at, double spread) {
  const Eigen::Vector3d o =
      from + Eigen::Vector3d{rng.Uniform(-50, 50), rng.Uniform(-50, 50), rng.Uniform(-50, 50)};
  const Eigen::Vector3d t =
      at + spread * Eigen::Vector3d{rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)};
  return {o, (t - o).normalized()};
}

TEST(Scene, PlaneHitsAreExact) {
  Scene scene;
  const Eigen::Isometry3d cell_from_rect = Pose(0.31, -0.22, 0.7, 412.3, -233.1, 187.9);
  SceneObject rect{"plate", MakeRectangle(cell_from_rect, 900, 700), {}};
  const AnalyticSurface plane = rect.geometry.patches[0];
  scene.Add(std::move(rect));
  scene.Commit();
  Rng rng(7);
  int hits = 0;
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    const auto [o, d] = RandomRay(rng, cell_from_rect * Eigen::Vector3d(30, -40, 900),
                                  cell_from_rect.translation(), 300);
    const auto hit = scene.Intersect(o, d);
    if (!hit) continue;
    ++hits;
    worst = std::max(worst, std::abs(plane.SignedDistance(hit->point)));
    EXPECT_NEAR((hit->point - o).norm(), hit->t_mm, 1e-9);
    EXPECT_NEAR(hit->normal.dot(plane.axis), 1.0, 1e-12);
  }
  EXPECT_GT(hits, 1500);
  EXPECT_LE(worst, kExactMm);
}

// Building a scene leaves the process's thread limit alone: Embree's "threads=N" device setting
// becomes a process-wide TBB limit, which made every later parallel loop of a process that had
// simulated (a benchmark, a test) run on one thread.
TEST(Scene, CommittingLeavesTheProcessThreadLimitAlone) {
  const std::size_t before =
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  Scene scene;
  scene.Add({"plate", MakeRectangle(Eigen::Isometry3d::Identity(), 100, 100), {}});
  scene.Commit();
  EXPECT_EQ(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
            before);
  EXPECT_GE(before, std::min<std::size_t>(2, std::max(1U, std::thread::hardware_concurrency())));
}

TEST(Scene, SphereHitsAreExactAlthoughTheMeshIsCoarse) {
  Scene scene;
  const Eigen::Isometry3d cell_from_sphere = Pose(0.1, 0.2, 0.3, -120.7, 351.2, 402.5);
  const double radius = 25.0;
  // 24 segments: the tessellation is up to r (1 - cos(pi/24)) ~ 0.2 mm inside the sphere, so
  // only the analytic refinement can pass the 1e-6 mm bound.
  SceneObject sphere{"sphere", MakeSphere(cell_from_sphere, radius, 24, 6), {}};
  const AnalyticSurface surface = sphere.geometry.patches[0];
  scene.Add(std::move(sphere));
  scene.Commit();
  Rng rng(11);
  int hits = 0;
  double worst = 0, worst_triangle = 0;
  for (int i = 0; i < 3000; ++i) {
    const auto [o, d] = RandomRay(rng, cell_from_sphere * Eigen::Vector3d(100, 600, 500),
                                  cell_from_sphere.translation(), radius * 0.9);
    const auto hit = scene.Intersect(o, d);
    if (!hit) continue;
    ++hits;
    worst = std::max(worst, std::abs(surface.SignedDistance(hit->point)));
    // The sphere faces the ray: outward normal against the direction.
    EXPECT_LT(hit->normal.dot(d), 0.0);
    const auto& g = scene.objects()[0].geometry;
    const auto& f = g.mesh.faces[hit->face];
    const Eigen::Vector3d n =
        (g.mesh.vertices.positions[f[1]] - g.mesh.vertices.positions[f[0]])
            .cross(g.mesh.vertices.positions[f[2]] - g.mesh.vertices.positions[f[0]])
            .normalized();
    const double t_tri = (g.mesh.vertices.positions[f[0]] - o).dot(n) / d.dot(n);
    worst_triangle = std::max(worst_triangle, std::abs(surface.SignedDistance(o + t_tri * d)));
  }
  EXPECT_GT(hits, 1000);
  EXPECT_LE(worst, kExactMm);
  EXPECT_GT(worst_triangle, 1e-2);  // the mesh alone is far from exact
}

TEST(Scene, CylinderHitsAreExact) {
  Scene scene;
  const Eigen::Isometry3d cell_from_cyl = Pose(0.4, 0.0, 0.2, 50, 60, 70);
  SceneObject cyl{"stand", MakeCylinder(cell_from_cyl, 20.0, 150.0, 32, true, true), {}};
  const AnalyticSurface wall = cyl.geometry.patches[0];
  scene.Add(std::move(cyl));
  scene.Commit();
  Rng rng(3);
  int wall_hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const auto [o, d] = RandomRay(rng, cell_from_cyl * Eigen::Vector3d(400, 0, 75),
                                  cell_from_cyl * Eigen::Vector3d(0, 0, 75), 18);
    const auto hit = scene.Intersect(o, d);
    if (!hit || scene.objects()[0].geometry.face_patch[hit->face] != 0) continue;
    ++wall_hits;
    EXPECT_LE(std::abs(wall.SignedDistance(hit->point)), kExactMm);
  }
  EXPECT_GT(wall_hits, 1000);
}

TEST(Scene, OcclusionAndMisses) {
  Scene scene;
  scene.Add({"floor", MakeRectangle(Eigen::Isometry3d::Identity(), 1000, 1000), {}});
  scene.Add(
      {"block", MakeBox(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 50)), {100, 100, 100}), {}});
  scene.Commit();
  const Eigen::Vector3d floor_point(300, 0, 0);
  // Seen from straight above: free. Seen from across the block: occluded.
  EXPECT_FALSE(scene.Occluded(floor_point, Eigen::Vector3d::UnitZ(), 0.01, 1000));
  const Eigen::Vector3d eye(-300, 0, 60);
  const Eigen::Vector3d to_eye = eye - floor_point;
  EXPECT_TRUE(scene.Occluded(floor_point, to_eye, 0.01, to_eye.norm() - 0.01));
  // Segment that stops before the block is free.
  EXPECT_FALSE(scene.Occluded(floor_point, to_eye, 0.01, 100));
  // Miss.
  EXPECT_FALSE(scene.Intersect({2000, 0, 10}, {1, 0, 0}).has_value());
  // The block's top is hit from above with an exact height.
  const auto hit = scene.Intersect({10.5, -20.25, 500}, {0.01, 0.02, -1});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(scene.objects()[hit->object].name, "block");
  EXPECT_NEAR(hit->point.z(), 100.0, 1e-12);
}

TEST(ChairSeat, MeshIsClosedAndOrientedWithTheHoleWhereItShouldBe) {
  const ChairSeat seat = MakeChairSeat();
  const auto& mesh = seat.part.mesh;
  // Every directed edge appears once and its reverse once: closed and consistently oriented.
  std::map<std::pair<int, int>, int> edges;
  for (const auto& f : mesh.faces) {
    for (int e = 0; e < 3; ++e) ++edges[{f[e], f[(e + 1) % 3]}];
  }
  for (const auto& [edge, count] : edges) {
    ASSERT_EQ(count, 1);
    ASSERT_EQ(edges.count({edge.second, edge.first}), 1u);
  }
  // Positive enclosed volume (outward normals), divergence theorem.
  double volume = 0;
  for (const auto& f : mesh.faces) {
    const auto& p = mesh.vertices.positions;
    volume += p[f[0]].dot(p[f[1]].cross(p[f[2]])) / 6.0;
  }
  EXPECT_GT(volume, 0.0);
  const BoundingBox box = mesh.vertices.Bounds();
  EXPECT_NEAR(box.Size().x(), 450.0, 1.0);
  EXPECT_NEAR(box.Size().y(), 450.0, 1.0);
  EXPECT_NEAR(box.min.z(), 0.0, 12.0);
  EXPECT_NEAR(box.max.z(), seat.hole_center_in_part.z(), 1e-9);

  // A ray straight down the hole axis passes through the part; one 5 mm off the axis (inside
  // the 13.5 mm hole radius) too; one 20 mm off hits the boss top.
  Scene scene;
  scene.Add({"seat", seat.part, {}});
  scene.Commit();
  const Eigen::Vector3d c = seat.hole_center_in_part;
  EXPECT_FALSE(scene.Intersect(c + Eigen::Vector3d(0, 0, 100), -Eigen::Vector3d::UnitZ()));
  EXPECT_FALSE(scene.Intersect(c + Eigen::Vector3d(5, 0, 100), -Eigen::Vector3d::UnitZ()));
  const auto top = scene.Intersect(c + Eigen::Vector3d(20, 0, 100), -Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(top.has_value());
  EXPECT_NEAR(top->point.z(), c.z(), 1e-9);
  // Hole wall hit horizontally from inside the hole lies on the 13.5 mm cylinder.
  const auto wall = scene.Intersect(c + Eigen::Vector3d(0, 0, -10), Eigen::Vector3d(1, 0.3, 0));
  ASSERT_TRUE(wall.has_value());
  const Eigen::Vector2d radial = (wall->point - c).head<2>();
  EXPECT_NEAR(radial.norm(), 13.5, kExactMm);
  EXPECT_LT(wall->normal.head<2>().dot(radial), 0.0);  // outward = towards the axis
}

TEST(ChairSeat, FreeFormHitsLieOnTheirTriangle) {
  const ChairSeat seat = MakeChairSeat();
  Scene scene;
  const Eigen::Isometry3d cell_from_seat = Pose(0.2, -0.1, 1.1, 100, 50, 300);
  MeshPart part = seat.part;
  part.Transform(cell_from_seat);
  scene.Add({"seat", part, {}});
  scene.Commit();
  Rng rng(5);
  int free_form = 0;
  for (int i = 0; i < 2000; ++i) {
    const auto [o, d] = RandomRay(rng, cell_from_seat * Eigen::Vector3d(0, 0, 900),
                                  cell_from_seat * Eigen::Vector3d(0, 0, 40), 200);
    const auto hit = scene.Intersect(o, d);
    if (!hit) continue;
    const auto& g = scene.objects()[0].geometry;
    if (g.patches[g.face_patch[hit->face]].kind != AnalyticSurface::Kind::kNone) continue;
    ++free_form;
    const auto& f = g.mesh.faces[hit->face];
    const auto& p = g.mesh.vertices.positions;
    const Eigen::Vector3d n = (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]).normalized();
    EXPECT_LE(std::abs((hit->point - p[f[0]]).dot(n)), kExactMm);
  }
  EXPECT_GT(free_form, 1000);
}

TEST(Geometry, PalletHasTheEuroDimensions) {
  const MeshPart pallet = MakePallet();
  const BoundingBox box = pallet.mesh.vertices.Bounds();
  EXPECT_NEAR(box.Size().x(), 1200.0, 1e-9);
  EXPECT_NEAR(box.Size().y(), 800.0, 1e-9);
  EXPECT_NEAR(box.max.z(), kPalletHeightMm, 1e-9);
  EXPECT_NEAR(box.min.z(), 0.0, 1e-9);
}

}  // namespace
}  // namespace lasercell::datasets
