#pragma once
// Test helpers for the robot-sphere calibrations: exact synthetic sphere sweeps on the
// simulator's planned poses (datasets PlanPoseSweeps: joints from the NOMINAL UR5's IK, the
// TRUE UR5 posing the sensor), with points computed analytically as laser plane ∩ sphere (upper
// half only, the side facing the camera) plus Gaussian noise along the camera ray, and a few
// floor points as clutter. Much faster than rendering, for Monte-Carlo tests.
// The simulation profile is the caller's SimConfig: it draws the truth (joint offsets, DH
// errors) and plans the poses; the points themselves are synthetic.

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "calib/joint_identification.hpp"
#include "datasets/calibration_captures.hpp"
#include "datasets/robots.hpp"
#include "datasets/simulate.hpp"

namespace lasercell::calib::testing {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

/// A planned pose set and the truth in vision_base.
struct PlannedPoses {
  datasets::SimConfig config;
  datasets::CellTruth truth;
  std::vector<datasets::PoseSweep> plans;
  std::vector<Eigen::Vector3d> centres_in_base;           ///< True sphere centres, vision_base.
  Eigen::Vector3d up_in_base = Eigen::Vector3d::UnitZ();  ///< Cell +z in vision_base.
};

inline PlannedPoses PlanPoses(const datasets::SimConfig& config,
                              const datasets::PoseSweepOptions& options, std::uint64_t seed) {
  PlannedPoses p;
  p.config = config;
  p.truth = datasets::MakeCellTruth(config);
  p.plans = datasets::PlanPoseSweeps(config, p.truth, options, seed, "test poses");
  const Eigen::Isometry3d base_from_cell = p.truth.layout.cell_from_vision_base.inverse();
  for (const Eigen::Vector3d& c : config.spheres.CentersInCell()) {
    p.centres_in_base.push_back(base_from_cell * c);
  }
  p.up_in_base = base_from_cell.linear().col(2);
  return p;
}

/// Moves pose i's sweep by range_offsets_mm[i % size] along the laser's central ray (the laser
/// plane stays where it is in space, so the sphere is still swept, at another range), re-solving
/// the joints on the nominal robot. Poses whose IK fails keep their plan.
inline void VaryRange(PlannedPoses& p, const std::vector<double>& range_offsets_mm) {
  const Eigen::Vector3d ray_in_sensor = p.truth.sensor.laser.center_in_sensor;
  const Eigen::Isometry3d base_from_cell = p.truth.layout.cell_from_vision_base.inverse();
  const Eigen::Isometry3d sensor_from_flange = p.truth.vision_flange_from_sensor.inverse();
  for (std::size_t i = 0; i < p.plans.size(); ++i) {
    datasets::PoseSweep& plan = p.plans[i];
    const double shift = range_offsets_mm[i % range_offsets_mm.size()];
    std::vector<std::vector<double>> joints;
    for (std::size_t w = 0; w < plan.commanded_cell_from_sensor.size(); ++w) {
      Eigen::Isometry3d cell_from_sensor = plan.commanded_cell_from_sensor[w];
      cell_from_sensor.translation() -= shift * (cell_from_sensor.linear() * ray_in_sensor);
      const auto q = datasets::SolveIk(p.truth.nominal_vision_robot,
                                       base_from_cell * cell_from_sensor * sensor_from_flange,
                                       plan.trajectory.joints_rad[w]);
      if (!q) break;
      joints.push_back(*q);
    }
    if (joints.size() == plan.trajectory.joints_rad.size()) plan.trajectory.joints_rad = joints;
  }
}

/// Sweeps of `profiles` exposures each along the planned trajectories, noise sigma_mm along the
/// ray, up to `points_per_profile` sphere points per profile and `clutter` floor points.
inline std::vector<SphereSweep> SyntheticSweeps(const PlannedPoses& p, int profiles,
                                                double sigma_mm, std::uint64_t seed,
                                                int points_per_profile = 40, int clutter = 10) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::Vector4d plane = p.truth.sensor.laser.Coefficients();
  const Eigen::Vector3d n = plane.head<3>();
  const double radius = p.config.spheres.radius_mm;
  std::vector<SphereSweep> sweeps;
  for (std::size_t i = 0; i < p.plans.size(); ++i) {
    const datasets::PoseSweep& plan = p.plans[i];
    SphereSweep sweep;
    sweep.name = "pose_" + std::to_string(i);
    sweep.sphere = plan.sphere;
    const double duration = plan.trajectory.times_s.back();
    for (int k = 0; k < profiles; ++k) {
      SweptProfile prof;
      prof.joints_rad = plan.trajectory.At(duration * k / std::max(1, profiles - 1));
      const Eigen::Isometry3d base_from_sensor =
          p.truth.true_vision_robot.BaseFromFlange(prof.joints_rad) *
          p.truth.vision_flange_from_sensor;
      const Eigen::Isometry3d sensor_from_base = base_from_sensor.inverse();
      const Eigen::Vector3d c = sensor_from_base * p.centres_in_base[plan.sphere];
      const Eigen::Vector3d up = sensor_from_base.linear() * p.up_in_base;
      const double dist = n.dot(c) + plane[3];
      if (std::abs(dist) < radius) {
        const Eigen::Vector3d m = c - dist * n;
        const double rho = std::sqrt(radius * radius - dist * dist);
        const Eigen::Vector3d u = n.unitOrthogonal();
        const Eigen::Vector3d v = n.cross(u);
        for (int s = 0; s < 4 * points_per_profile; ++s) {
          const double phi = 2 * 3.14159265358979323846 * (s + 0.5) / (4 * points_per_profile);
          const Eigen::Vector3d q = m + rho * (std::cos(phi) * u + std::sin(phi) * v);
          if ((q - c).dot(up) < 0 || (q - c).dot(q) > 0) continue;  // lower half or back side
          prof.points_in_sensor.push_back(q + sigma_mm * noise(rng) * q.normalized());
        }
      }
      // Clutter: the laser line on a floor 150 mm below the sphere centre.
      const Eigen::Vector3d floor_point = c - 150 * up;
      for (int s = 0; s < clutter; ++s) {
        // A point on both the laser plane and the floor, then along their intersection line.
        const Eigen::Vector3d line_dir = n.cross(up).normalized();
        Eigen::Matrix<double, 2, 3> a;
        a << n.transpose(), up.transpose();
        const Eigen::Vector2d b(-plane[3], up.dot(floor_point));
        const Eigen::Vector3d base_pt = a.transpose() * (a * a.transpose()).inverse() * b;
        const Eigen::Vector3d q = base_pt + (s - clutter / 2.0) * 15.0 * line_dir;
        if (q.z() > 0) prof.points_in_sensor.push_back(q);
      }
      sweep.profiles.push_back(std::move(prof));
    }
    sweeps.push_back(std::move(sweep));
  }
  return sweeps;
}

/// A sensor-frame point at the laser's stand-off (where measurements happen), placed in the
/// base by a model and a hand-eye transform.
inline Eigen::Vector3d MeasuredPointInBase(const DhChain& robot,
                                           const Eigen::Isometry3d& flange_from_sensor,
                                           const std::vector<double>& joints) {
  return robot.BaseFromFlange(joints) * flange_from_sensor * Eigen::Vector3d(0, 0, 700);
}

}  // namespace lasercell::calib::testing
