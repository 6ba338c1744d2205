#pragma once
// Synthetic sphere caps sampled like the simulated sensor (test helper).
//
// Sampling density of the default simulated linear sweep (datasets/SIMULATOR.md): 900 mm over
// 350 profiles = 2.58 mm between profiles (along x), and 10.6 um pixels * ~610 mm range / 12 mm
// lens = 0.54 mm between columns (along y). The cap is seen from +z (the sensor above): a point
// is kept when its polar angle from +z is <= max_polar_deg (85 deg: the renderer's grazing
// cutoff). Noise: isotropic Gaussian, sigma per axis.

#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <vector>

#include "datasets/rng.hpp"

namespace lasercell::calib::testing {

inline constexpr double kProfileSpacingMm = 900.0 / 349.0;
inline constexpr double kColumnSpacingMm = 0.54;

inline std::vector<Eigen::Vector3d> SampleCap(const Eigen::Vector3d& center, double radius,
                                              double max_polar_deg, double sigma,
                                              datasets::Rng& rng,
                                              double spacing_x = kProfileSpacingMm,
                                              double spacing_y = kColumnSpacingMm) {
  const double rho_max = radius * std::sin(std::min(max_polar_deg, 90.0) * std::numbers::pi / 180);
  const double ox = rng.Uniform(0, spacing_x), oy = rng.Uniform(0, spacing_y);
  std::vector<Eigen::Vector3d> points;
  for (double x = -radius + ox; x <= radius; x += spacing_x) {
    for (double y = -radius + oy; y <= radius; y += spacing_y) {
      const double rho2 = x * x + y * y;
      if (rho2 > rho_max * rho_max) continue;
      const Eigen::Vector3d p(x, y, std::sqrt(radius * radius - rho2));
      const Eigen::Vector3d noise{rng.Normal() * sigma, rng.Normal() * sigma, rng.Normal() * sigma};
      points.push_back(center + p + noise);
    }
  }
  return points;
}

}  // namespace lasercell::calib::testing
