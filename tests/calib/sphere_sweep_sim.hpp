#pragma once
// Test helper (not library code): the simulated spheres sweep as a point cloud in the sweep
// frame, built the way `lasercell scan triangulate` does: render the spheres
// capture with the datasets API, triangulate every peak with the TRUE camera
// (calib::CameraModel::Unproject) and the TRUE laser plane, and place it by the linear sweep
// motion. Sweep frame = the sensor frame at the sweep start (t = 0):
//   p_in_sweep = cell_from_sensor(0)^-1 * cell_from_sensor(t) * p_in_sensor
//              = p_in_sensor + R0^T * velocity * t           (pure translation, linear sweep)
// Truth: handling_base_from_sweep = cell_from_handling_base^-1 * cell_from_sensor(0).

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <vector>

#include "calib/sphere_segmentation.hpp"
#include "core/point_cloud.hpp"
#include "datasets/calibration_captures.hpp"
#include "datasets/cell.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/rng.hpp"
#include "datasets/simulate.hpp"

namespace lasercell::calib::testing {

struct SimulatedSphereSweep {
  PointCloud cloud;  ///< In the sweep frame, with profile/column/timestamp.
  Eigen::Isometry3d handling_base_from_sweep = Eigen::Isometry3d::Identity();  ///< Truth.
  std::vector<Eigen::Vector3d> centers_in_sweep;                               ///< Truth.
  std::vector<Eigen::Vector3d> centers_in_handling_base;                       ///< Truth.
  std::vector<datasets::Touch> touches;  ///< Simulated touches (noisy).
  double radius_mm = 0;
};

/// Renders and triangulates the spheres sweep of `config` (random stream `seed`). The simulation
/// profile is the caller's: whatever `config` holds.
inline SimulatedSphereSweep SimulateSphereSweep(const datasets::SimConfig& config,
                                                std::uint64_t seed) {
  using namespace lasercell::datasets;
  const CellTruth truth = MakeCellTruth(config);
  const Scene scene = MakeSphereScene(truth.layout, config.spheres);
  const LaserRenderer renderer(scene, truth.sensor, config.render);
  const LinearSweep sweep = MakeLinearSweep(config, truth.sensor);
  const SweepResult rendered = RenderSweep(
      renderer,
      [&](double t) {
        return SensorState{sweep.At(t), {}};
      },
      config.timing, seed, 0, "", 1);
  SimulatedSphereSweep out;
  out.radius_mm = config.spheres.radius_mm;
  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  out.handling_base_from_sweep = hb_from_cell * sweep.cell_from_sensor_start;
  for (const Eigen::Vector3d& c : config.spheres.CentersInCell()) {
    out.centers_in_sweep.push_back(sweep.cell_from_sensor_start.inverse() * c);
    out.centers_in_handling_base.push_back(hb_from_cell * c);
  }
  const Eigen::Vector4d plane = truth.sensor.laser.Coefficients();
  const Eigen::Vector3d v_in_sweep =
      sweep.cell_from_sensor_start.linear().transpose() * sweep.velocity_mm_s;
  const auto& header = rendered.profiles.header;
  for (std::size_t i = 0; i < rendered.profiles.profiles.size(); ++i) {
    const auto& profile = rendered.profiles.profiles[i];
    const double t = static_cast<double>(profile.timestamp_ns - config.timing.start_ns) * 1e-9;
    for (std::size_t c = 0; c < profile.row_px.size(); ++c) {
      const float row = profile.row_px[c];
      if (!std::isfinite(row)) continue;
      const Eigen::Vector2d pixel(static_cast<double>(header.first_column + c), row);
      const Eigen::Vector3d ray = truth.sensor.camera.Unproject(pixel);
      const double denom = plane.head<3>().dot(ray);
      if (std::abs(denom) < 1e-12) continue;
      const Eigen::Vector3d p_in_sensor = (-plane[3] / denom) * ray;
      out.cloud.positions.push_back(p_in_sensor + v_in_sweep * t);
      out.cloud.profile.push_back(static_cast<std::int32_t>(i));
      out.cloud.column.push_back(static_cast<std::int32_t>(c));
      out.cloud.timestamp_s.push_back(t);
    }
  }
  out.touches = SimulateTouches(config, truth, StreamSeed(seed, 0x6000));
  return out;
}

/// The default simulated cell's spheres sweep, rendered once per test binary (seed 7).
/// Simulation profile: ideal (SimConfig{}; a regression check of the algorithms' own error).
inline const SimulatedSphereSweep& DefaultSphereSweep() {
  static const SimulatedSphereSweep sweep = [] {
    datasets::SimConfig config;
    config.seed = 7;
    return SimulateSphereSweep(config, datasets::StreamSeed(7, 0x5F));
  }();
  return sweep;
}

/// SegmentSpheres (default options) on DefaultSphereSweep(), computed once per test binary.
inline const SphereSegmentationResult& DefaultSphereSegmentation() {
  static const SphereSegmentationResult seg = SegmentSpheres(DefaultSphereSweep().cloud);
  return seg;
}

}  // namespace lasercell::calib::testing
