// CalibrateHalfSpheresInSweep (segmentation + calibration), its result JSON and report, and the
// edge checks `calibrate spheres` runs before it.
// Simulation profile: ideal (DefaultSphereSweep, tests/calib/sphere_sweep_sim.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "calib/half_sphere_calibration.hpp"
#include "calib/half_sphere_report.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/se3.hpp"
#include "tests/calib/sphere_sweep_sim.hpp"

namespace lasercell::calib {
namespace {

SphereTouches TouchesOf(const testing::SimulatedSphereSweep& sim) {
  SphereTouches t;
  t.sphere_radius_mm = sim.radius_mm;
  t.stated_sigma_mm = 0.05;
  for (const auto& s : sim.touches) {
    t.touches.push_back({s.sphere, s.measured_in_handling_base, s.joints_rad});
  }
  return t;
}

TEST(CalibrateHalfSpheresInSweep, ComposesSegmentationAndCalibration) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  const SphereTouches touches = TouchesOf(sim);
  const HalfSphereSweepResult run = CalibrateHalfSpheresInSweep(sim.cloud, touches, {});
  ASSERT_TRUE(run.calibrated) << run.failure;
  EXPECT_EQ(run.radius_mm, sim.radius_mm);  // from the touches
  EXPECT_EQ(run.touch_sigma_mm, 0.05);      // stated_sigma_mm
  EXPECT_EQ(run.segmentation.spheres.size(), 4u);
  // The same as the two steps by hand.
  HalfSphereCalibrationOptions options;
  options.touch_sigma_mm = 0.05;
  const HalfSphereCalibrationResult by_hand = CalibrateHalfSpheres(
      SweptSpheresFrom(testing::DefaultSphereSegmentation()), touches.touches, options);
  EXPECT_TRUE(
      run.calibration.handling_base_from_sweep.isApprox(by_hand.handling_base_from_sweep, 1e-12));
  EXPECT_LT(
      RotationDistance(run.calibration.handling_base_from_sweep, sim.handling_base_from_sweep),
      1e-3);

  HalfSphereInputNames names{"cell.yaml", "spheres.ply", "touches.yaml", "sweep_start"};
  const StaticEdge edge = HalfSphereEdge(run.calibration, names.sweep_frame,
                                         HalfSphereProvenance(run.calibration, "fnv1a64:0"));
  EXPECT_EQ(edge.child, "sweep_start");
  EXPECT_EQ(edge.provenance.tool.rfind("lasercell calibrate spheres ", 0), 0u);
  EXPECT_EQ(edge.provenance.residual_summary.rfind("rms ", 0), 0u);
  const nlohmann::json j = HalfSphereResultJson(run, names, edge);
  EXPECT_EQ(j["format"], "lasercell.calibration_spheres");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["edge"]["child"], "sweep_start");
  EXPECT_EQ(j["handling_base_from_sweep_start"]["rotation_wxyz"].size(), 4u);
  EXPECT_EQ(j["pose"], j["handling_base_from_sweep_start"]);
  EXPECT_EQ(j["inputs"]["digest"], "fnv1a64:0");
  EXPECT_EQ(j["spheres"].size(), 4u);
  EXPECT_EQ(j["covariance"]["values"].size(), 36u);
  const std::string html = HalfSphereReport(run, names).Html();
  EXPECT_NE(html.find("handling_base_from_sweep_start"), std::string::npos);
  EXPECT_NE(html.find("Per-sphere residuals"), std::string::npos);
}

// The response to a sensor's error modes (options.point_displacements) against moving the
// points: exactly E M^-1 for a rigid move M of the whole sweep (a translation, a rotation about
// the cloud's centroid), and a full re-segmentation and calibration of the moved cloud for a
// non-rigid one (a depth scale, like an offset error of the laser plane).
TEST(CalibrateHalfSpheresInSweep, ModeResponseFollowsThePointsMovedByEachMode) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  const SphereTouches touches = TouchesOf(sim);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : sim.cloud.positions) centroid += p;
  centroid /= static_cast<double>(sim.cloud.size());
  const Eigen::Vector3d t(0.03, -0.02, 0.05), w(1e-4, -2e-4, 5e-5);
  const double scale = 1e-4;
  const auto modes = [&](std::size_t i) {
    const Eigen::Vector3d& p = sim.cloud.positions[i];
    Eigen::Matrix<double, 3, Eigen::Dynamic> d(3, 3);
    d.col(0) = t;
    d.col(1) = w.cross(p - centroid);
    d.col(2) = Eigen::Vector3d(0, 0, scale * p.z());
    return d;
  };
  HalfSphereSweepOptions options;
  options.point_displacements = modes;
  const HalfSphereSweepResult run = CalibrateHalfSpheresInSweep(sim.cloud, touches, options);
  ASSERT_TRUE(run.calibrated) << run.failure;
  ASSERT_EQ(run.mode_response.cols(), 3);
  const Eigen::Isometry3d e = run.calibration.handling_base_from_sweep;
  const auto rigid = [&](const Eigen::Isometry3d& m) {
    return Vector6d(RotationVectorTranslation(e * m.inverse() * e.inverse()));
  };
  const Vector6d by_translation = rigid(Eigen::Isometry3d(Eigen::Translation3d(t)));
  const Vector6d by_rotation =
      rigid(Eigen::Translation3d(centroid) * Eigen::AngleAxisd(w.norm(), w.normalized()) *
            Eigen::Translation3d(-centroid));
  EXPECT_LT((run.mode_response.col(0) - by_translation).norm(), 1e-4 * by_translation.norm())
      << run.mode_response.col(0).transpose() << " vs " << by_translation.transpose();
  EXPECT_LT((run.mode_response.col(1) - by_rotation).norm(), 2e-2 * by_rotation.norm())
      << run.mode_response.col(1).transpose() << " vs " << by_rotation.transpose();
  // The depth scale: the whole step again on the moved clouds.
  Vector6d side[2];
  for (int s = 0; s < 2; ++s) {
    PointCloud moved = sim.cloud;
    for (std::size_t i = 0; i < moved.size(); ++i) {
      moved.positions[i] += (s == 0 ? 1.0 : -1.0) * modes(i).col(2);
    }
    const HalfSphereSweepResult r = CalibrateHalfSpheresInSweep(moved, touches, {});
    ASSERT_TRUE(r.calibrated) << r.failure;
    side[s] = RotationVectorTranslation(r.calibration.handling_base_from_sweep * e.inverse());
  }
  const Vector6d brute = 0.5 * (side[0] - side[1]);
  std::printf("[ measured ] depth-scale mode: response %s, refitted %s\n",
              ::testing::PrintToString(run.mode_response.col(2).transpose().eval()).c_str(),
              ::testing::PrintToString(brute.transpose().eval()).c_str());
  EXPECT_GT(brute.tail<3>().norm(), 0.01);  // the mode moves the placement measurably
  EXPECT_LT((run.mode_response.col(2) - brute).norm(), 0.05 * brute.norm());
}

// The radius tolerance's term against spheres that really are bigger: each sphere's inlier
// points pushed out by 0.05 mm along their fit's radial direction (a sphere 0.05 mm larger
// there) and its touch raised by as much, recalibrated; the squared pose changes, summed over
// the spheres and scaled to 1 sigma of the tolerance, are the term.
TEST(CalibrateHalfSpheresInSweep, RadiusToleranceCountsSpheresThatAreBiggerThanStated) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  SphereTouches touches = TouchesOf(sim);
  const HalfSphereSweepResult plain = CalibrateHalfSpheresInSweep(sim.cloud, touches, {});
  ASSERT_TRUE(plain.calibrated) << plain.failure;
  EXPECT_EQ(plain.radius_tolerance_mm, 0.0);  // none stated
  EXPECT_TRUE(plain.radius_covariance.isZero());
  touches.sphere_radius_tolerance_mm = 0.05;
  const HalfSphereSweepResult run = CalibrateHalfSpheresInSweep(sim.cloud, touches, {});
  ASSERT_TRUE(run.calibrated) << run.failure;
  EXPECT_EQ(run.radius_tolerance_mm, 0.05);
  EXPECT_TRUE(run.calibration.covariance.isApprox(
      plain.calibration.covariance + run.radius_covariance, 1e-12));

  const double step = 0.05, sigma = 0.05 / std::sqrt(3.0);
  const Eigen::Isometry3d base_inverse = plain.calibration.handling_base_from_sweep.inverse();
  Matrix6d expected = Matrix6d::Zero();
  for (const HalfSphereResidual& matched : plain.calibration.spheres) {
    const SegmentedSphere& s = plain.segmentation.spheres[matched.swept];
    PointCloud bigger = sim.cloud;
    for (std::size_t j = 0; j < s.indices.size(); ++j) {
      Eigen::Vector3d& p = bigger.positions[s.indices[j]];
      p += step * (p - s.fit.center).normalized();
    }
    SphereTouches raised = TouchesOf(sim);
    for (SphereTouch& t : raised.touches) {
      if (t.sphere == matched.sphere) t.point_in_handling_base.z() += step;
    }
    const HalfSphereSweepResult moved = CalibrateHalfSpheresInSweep(bigger, raised, {});
    ASSERT_TRUE(moved.calibrated) << moved.failure;
    const Vector6d xi =
        RotationVectorTranslation(moved.calibration.handling_base_from_sweep * base_inverse) *
        (sigma / step);
    expected += xi * xi.transpose();
  }
  // Within 10 %: the term is first order, the recalibration re-segments and refits (on this
  // sweep the largest difference, along z, was 5.4 %).
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(std::sqrt(run.radius_covariance(k, k)), std::sqrt(expected(k, k)),
                0.1 * std::sqrt(expected(k, k)) + 1e-7)
        << "coordinate " << k;
  }
  EXPECT_GT(run.radius_covariance.diagonal().tail<3>().maxCoeff(), 1e-6);  // not nothing

  HalfSphereSweepOptions options;
  options.radius_tolerance_mm = 0.0;  // the option overrides the file
  EXPECT_TRUE(CalibrateHalfSpheresInSweep(sim.cloud, touches, options).radius_covariance.isZero());
  options.free_radius = true;  // fitted radii: nothing to add
  options.radius_tolerance_mm = -1;
  EXPECT_TRUE(CalibrateHalfSpheresInSweep(sim.cloud, touches, options).radius_covariance.isZero());
}

TEST(CalibrateHalfSpheresInSweep, NoSphereInTheSweepIsReportedNotThrown) {
  PointCloud floor;
  for (int i = 0; i < 60; ++i) {
    for (int k = 0; k < 60; ++k) floor.positions.emplace_back(2.0 * i, 2.0 * k, 700.0);
  }
  HalfSphereSweepOptions options;
  options.sweep_unit_hint = "the points look like metres";
  const HalfSphereSweepResult run = CalibrateHalfSpheresInSweep(
      floor, TouchesOf(testing::DefaultSphereSweep()), options, {"", "floor.ply", "t.yaml"});
  EXPECT_FALSE(run.calibrated);
  EXPECT_EQ(run.failure.rfind("no sphere of radius 25 mm found (0 spheres", 0), 0u) << run.failure;
  EXPECT_NE(run.failure.find("; the points look like metres"), std::string::npos) << run.failure;
}

TEST(CalibrateHalfSpheresInSweep, TheRadiusMustComeFromSomewhere) {
  SphereTouches touches = TouchesOf(testing::DefaultSphereSweep());
  touches.sphere_radius_mm.reset();
  try {
    CalibrateHalfSpheresInSweep(PointCloud{}, touches, {}, {"", "s.ply", "t.yaml"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "t.yaml: no sphere_radius_mm; give --radius-mm R");
  }
}

TEST(CalibrateHalfSpheresInSweep, DegeneraciesNameBothInputs) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  SphereTouches touches = TouchesOf(sim);
  touches.touches.resize(2);
  try {
    CalibrateHalfSpheresInSweep(sim.cloud, touches, {}, {"", "s.ply", "t.yaml"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("s.ply + t.yaml: half-sphere calibration: 2 sphere "
                                          "touches",
                                          0),
              0u)
        << e.what();
  }
}

TEST(CheckHalfSphereEdgeFits, RefusesACycleButReplacesItsOwnEdge) {
  FrameGraph graph;
  for (const char* f : {"handling_base", "cell", "sensor"}) graph.AddFrame(f);
  StaticEdge a;
  a.parent = "cell";
  a.child = "handling_base";
  graph.SetStaticEdge(a);
  StaticEdge b;
  b.parent = "cell";
  b.child = "sensor";
  graph.SetStaticEdge(b);
  try {
    CheckHalfSphereEdgeFits(graph, "sensor", "cell.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cell.yaml: handling_base and 'sensor' are already "
                                         "connected"),
              std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(CheckHalfSphereEdgeFits(graph, "sweep_start", "cell.yaml"));
  FrameGraph own;
  for (const char* f : {"handling_base", "sensor"}) own.AddFrame(f);
  StaticEdge e;
  e.parent = "handling_base";
  e.child = "sensor";
  own.SetStaticEdge(e);
  EXPECT_NO_THROW(CheckHalfSphereEdgeFits(own, "sensor", "cell.yaml"));
}

}  // namespace
}  // namespace lasercell::calib
