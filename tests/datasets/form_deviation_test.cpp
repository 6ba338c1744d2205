// The form deviation the simulator states in the seat's part file: closest points on triangles
// against dense sampling, a mesh against a shifted copy of itself, and the seat's CAD against
// the part the sensor sees, warped or not.

#include "datasets/form_deviation.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"
#include "core/random.hpp"
#include "datasets/chair_parts.hpp"
#include "datasets/chair_seat.hpp"
#include "datasets/sim_profile.hpp"

namespace lasercell::datasets {
namespace {

// The closest point must be no farther than any of 20000 points spread over the triangle, and
// no more than their spacing nearer: points around random triangles land in every Voronoi
// region (three vertices, three edges, the face).
TEST(ClosestPointOnTriangle, IsTheNearestPointOfTheTriangle) {
  std::mt19937_64 rng(71);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  const auto random_point = [&] { return Draws<3>(u, rng); };
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d a = random_point(), b = random_point(), c = random_point();
    const Eigen::Vector3d p = 2.0 * random_point();
    const Eigen::Vector3d q = ClosestPointOnTriangle(p, a, b, c);
    // q lies in the triangle's plane; the bounds below pin its distance from p to that of the
    // triangle's nearest sample, so a point outside the triangle nearer to p would fail them.
    const Eigen::Vector3d n = (b - a).cross(c - a);
    EXPECT_NEAR(n.normalized().dot(q - a), 0.0, 1e-9);
    double best = 1e300;
    constexpr int kSteps = 200;
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = 0; i + j <= kSteps; ++j) {
        const Eigen::Vector3d s = a + (b - a) * i / kSteps + (c - a) * j / kSteps;
        best = std::min(best, (s - p).norm());
      }
    }
    const double spacing = std::max({(b - a).norm(), (c - a).norm()}) / kSteps;
    EXPECT_LE((q - p).norm(), best + 1e-9) << "trial " << trial;
    EXPECT_GE((q - p).norm(), best - spacing) << "trial " << trial;
  }
}

TriangleMesh Grid(double side_mm, int n, double z_mm) {
  TriangleMesh m;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      m.vertices.positions.emplace_back(side_mm * i / n, side_mm * j / n, z_mm);
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int v = i * (n + 1) + j;
      m.faces.emplace_back(v, v + n + 1, v + 1);
      m.faces.emplace_back(v + 1, v + n + 1, v + n + 2);
    }
  }
  return m;
}

TEST(MeasureMeshDeviation, AFinerCopyLiftedOffTheModelIsOffByTheLift) {
  const MeshDeviation d = MeasureMeshDeviation(Grid(100.0, 37, 0.25), Grid(100.0, 5, 0.0));
  EXPECT_EQ(d.samples, 38u * 38u);
  EXPECT_NEAR(d.rms_mm, 0.25, 1e-12);
  EXPECT_NEAR(d.max_mm, 0.25, 1e-12);
  EXPECT_THROW(MeasureMeshDeviation(TriangleMesh{}, Grid(1.0, 1, 0.0)), InputError);
  EXPECT_THROW(MeasureMeshDeviation(Grid(1.0, 1, 0.0), TriangleMesh{}), InputError);
}

// The realistic profile's seat: a finer tessellation of the CAD's shell with a 0.5 mm saddle
// warp. Its deviation is at most the warp plus the CAD's chords (a few tenths of a mm) and, the
// warp vanishing about the boss, well below the warp in RMS; the part file states it. The ideal
// profile renders the CAD itself: nothing is stated.
TEST(SeatPartDefinition, StatesHowFarThePartTheSensorSeesIsFromItsCad) {
  const SimConfig realistic = SimConfigForProfile("realistic");
  const ChairSeat cad = MakeChairSeat(realistic.seat_shape);
  const ChairSeat seen = MakeRenderedChairSeat(realistic.seat_shape, realistic.seat_render);
  const MeshDeviation d = MeasureMeshDeviation(seen.part.mesh, cad.part.mesh);
  EXPECT_GT(d.max_mm, 0.5 * realistic.seat_render.warp_mm);
  EXPECT_LT(d.max_mm, realistic.seat_render.warp_mm + 0.5);
  EXPECT_GT(d.rms_mm, 0.05);
  EXPECT_LT(d.rms_mm, 0.6 * realistic.seat_render.warp_mm);
  const localize::PartDefinition stated = SeatPartDefinition(cad, &seen);
  EXPECT_GE(stated.form_deviation.rms_mm, d.rms_mm);
  EXPECT_LT(stated.form_deviation.rms_mm, d.rms_mm + 0.01);

  const SimConfig ideal = SimConfigForProfile("ideal");
  const ChairSeat ideal_cad = MakeChairSeat(ideal.seat_shape);
  const ChairSeat ideal_seen = MakeRenderedChairSeat(ideal.seat_shape, ideal.seat_render);
  EXPECT_EQ(SeatPartDefinition(ideal_cad, &ideal_seen).form_deviation.rms_mm, 0.0);
  EXPECT_EQ(SeatPartDefinition(cad).form_deviation.rms_mm, 0.0);
}

}  // namespace
}  // namespace lasercell::datasets
