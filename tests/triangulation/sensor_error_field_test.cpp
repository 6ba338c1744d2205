#include "triangulation/sensor_error_field.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "calib/camera_model.hpp"
#include "core/error.hpp"
#include "datasets/sensor.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::triangulation {
namespace {

using ::testing::HasSubstr;

struct Sensor {
  datasets::SensorModel sensor = datasets::MakeSensor(datasets::SensorOptions{});
  calib::CameraModel camera = sensor.camera;
  Eigen::Vector4d plane = sensor.laser.Coefficients();

  LaserPlaneEntry Entry(const std::vector<SensorErrorMode>& modes) const {
    LaserPlaneEntry e;
    e.normal = plane.head<3>();
    e.point_mm = -plane[3] * plane.head<3>();
    e.error_modes = modes;
    return e;
  }
};

// A camera mode (OPENCV8: fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6) with the plane step that goes
// with it, and a plane-only mode: a normal step perpendicular to n (it stays unit to first
// order) and an offset step.
std::vector<SensorErrorMode> Modes(const Eigen::Vector3d& n) {
  SensorErrorMode camera;
  camera.intrinsics_step = {0.3, 0.25, -0.12, 0.08, 2e-4, -1e-4, 3e-5, -2e-5, 1e-5, 1e-4, 0, 0};
  const Eigen::Vector3d t = n.unitOrthogonal();
  camera.plane_step << 2e-5 * t, 0.01;
  SensorErrorMode plane;
  plane.plane_step << -3e-5 * n.cross(t), -0.02;
  return {camera, plane};
}

// Against triangulating the same pixel through the stepped camera and plane (central
// differences): the first-order system is the derivative of ray-plane triangulation.
TEST(SensorErrorField, DisplacementsAreTheDerivativeOfRetriangulatingThePixel) {
  const Sensor s;
  const std::vector<SensorErrorMode> modes = Modes(s.plane.head<3>());
  const SensorErrorField field(s.camera, s.Entry(modes));
  ASSERT_EQ(field.Modes(), 2);
  const Triangulator nominal(s.camera, s.plane);
  const double h = 1e-2;
  for (std::size_t k = 0; k < modes.size(); ++k) {
    std::vector<Triangulator> stepped;
    for (double sign : {1.0, -1.0}) {
      std::vector<double> intrinsics = s.camera.intrinsics();
      for (std::size_t i = 0; i < modes[k].intrinsics_step.size(); ++i) {
        intrinsics[i] += sign * h * modes[k].intrinsics_step[i];
      }
      Eigen::Vector4d plane = s.plane + sign * h * modes[k].plane_step;
      plane /= plane.head<3>().norm();
      stepped.emplace_back(calib::CameraModel(s.camera.lensmodel(), intrinsics, s.camera.width_px(),
                                              s.camera.height_px()),
                           plane);
    }
    int checked = 0;
    for (int u = 20; u < 1024; u += 97) {
      for (double v = 10.5; v < 1024; v += 113.0) {
        const Eigen::Vector3d p = nominal.TriangulateExact(u, v);
        const Eigen::Vector3d a = stepped[0].TriangulateExact(u, v);
        const Eigen::Vector3d b = stepped[1].TriangulateExact(u, v);
        if (!p.allFinite() || !a.allFinite() || !b.allFinite()) continue;
        const Eigen::Vector3d expected = (a - b) / (2 * h);
        const Eigen::Vector3d got = field.Displacements(p).col(static_cast<Eigen::Index>(k));
        EXPECT_LT((got - expected).norm(), 1e-4 * expected.norm() + 1e-9)
            << "mode " << k << " pixel " << u << ", " << v;
        EXPECT_GT(expected.norm(), 1e-4);  // the step moves the point measurably
        ++checked;
      }
    }
    EXPECT_GT(checked, 30);
  }
}

// The plane-only mode is dp = p (p^T dn + dd) / d.
TEST(SensorErrorField, PlaneOnlyModeIsTheClosedForm) {
  const Sensor s;
  const std::vector<SensorErrorMode> modes = Modes(s.plane.head<3>());
  const SensorErrorField field(s.camera, s.Entry(modes));
  const Triangulator nominal(s.camera, s.plane);
  const Eigen::Vector3d p = nominal.TriangulateExact(500, 400.5);
  ASSERT_TRUE(p.allFinite());
  const Eigen::Vector4d& step = modes[1].plane_step;
  const Eigen::Vector3d closed = p * (p.dot(step.head<3>()) + step[3]) / s.plane[3];
  EXPECT_LT((field.Displacements(p).col(1) - closed).norm(), 1e-9 * closed.norm());
}

TEST(SensorErrorField, BadInputIsNamed) {
  const Sensor s;
  EXPECT_THROW(
      {
        try {
          SensorErrorField(s.camera, s.Entry({}));
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), HasSubstr("no error_modes"));
          throw;
        }
      },
      InputError);
  std::vector<SensorErrorMode> modes = Modes(s.plane.head<3>());
  modes[0].intrinsics_step.resize(9);
  EXPECT_THROW(
      {
        try {
          SensorErrorField(s.camera, s.Entry(modes));
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), HasSubstr("steps 9 intrinsics but the camera"));
          throw;
        }
      },
      InputError);
  PointCloud cloud;
  cloud.positions = {Eigen::Vector3d(0, 0, 300)};
  const SensorErrorField field(s.camera, s.Entry(Modes(s.plane.head<3>())));
  EXPECT_THROW(CloudPointDisplacements(field, cloud, {Eigen::Isometry3d::Identity()}), InputError);
  cloud.profile = {3};
  EXPECT_THROW(CloudPointDisplacements(field, cloud, {Eigen::Isometry3d::Identity()}), InputError);
}

// A cloud point's displacement is the field at its sensor-frame position, turned into the
// cloud's frame by its profile's pose.
TEST(SensorErrorField, CloudPointsUseTheirProfilesSensorPose) {
  const Sensor s;
  const SensorErrorField field(s.camera, s.Entry(Modes(s.plane.head<3>())));
  const Triangulator nominal(s.camera, s.plane);
  const Eigen::Vector3d p = nominal.TriangulateExact(600, 300.25);
  ASSERT_TRUE(p.allFinite());
  const Eigen::Isometry3d frame_from_sensor =
      Eigen::Translation3d(10, 250, -40) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY());
  PointCloud cloud;
  cloud.positions = {p, frame_from_sensor * p};
  cloud.profile = {0, 1};
  const auto displace =
      CloudPointDisplacements(field, cloud, {Eigen::Isometry3d::Identity(), frame_from_sensor});
  const Eigen::Matrix<double, 3, Eigen::Dynamic> d0 = displace(0);
  EXPECT_LT((displace(1) - frame_from_sensor.linear() * d0).norm(), 1e-9 * d0.norm());
}

}  // namespace
}  // namespace lasercell::triangulation
