#pragma once
// Helpers shared by the registration tests: real UWA data (cached per test binary), seeded
// synthetic shapes with exact normals, random poses, a simulated single-view scan, pose
// comparison by model-point displacement, and the committed rs1 reference pose. The synthetic
// rs1 scenes are datasets/synthetic_scan.hpp's (one implementation with `lasercell bench
// robustness`), wrapped here with the real inputs cached.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include "core/error.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/point_cloud.hpp"
#include "core/random.hpp"
#include "core/se3.hpp"
#include "datasets/synthetic_scan.hpp"
#include "registration/kdtree.hpp"
#include "registration/normals.hpp"
#include "registration/reference_pose.hpp"
#include "registration/viewpoint.hpp"

namespace lasercell::registration::test {

/// Path of a bundled real data file (datasets/real/<set>/<file>); empty if absent.
inline std::string RealDataFile(const std::string& set, const std::string& file) {
  const std::string path = std::string(LASERCELL_SOURCE_DIR) + "/datasets/real/" + set + "/" + file;
  return std::filesystem::is_regular_file(path) ? path : std::string();
}

/// The UWA parasaurolophus model (6700 points, unnormalized normals as shipped), or nullptr.
inline const PointCloud* UwaModel() {
  static const PointCloud* cloud = [] {
    const std::string path = RealDataFile("uwa", "parasaurolophus_6700.ply");
    return path.empty() ? nullptr : new PointCloud(io::ReadPointCloud(path));
  }();
  return cloud;
}

/// The UWA scene rs1 (114k points with normals), or nullptr.
inline const PointCloud* UwaScene() {
  static const PointCloud* cloud = [] {
    const std::string path = RealDataFile("uwa", "rs1_normals.bin.ply");
    return path.empty() ? nullptr : new PointCloud(io::ReadPointCloud(path));
  }();
  return cloud;
}

#define LASERCELL_REQUIRE_UWA()                                                               \
  if (::lasercell::registration::test::UwaModel() == nullptr ||                               \
      ::lasercell::registration::test::UwaScene() == nullptr)                                 \
  GTEST_FAIL() << "bundled UWA data (parasaurolophus_6700.ply, rs1_normals.bin.ply) missing " \
                  "from datasets/real/uwa"

/// The committed reference pose scene_from_model of the parasaurolophus in rs1.
inline Eigen::Isometry3d Rs1ReferencePose() {
  return datasets::ReadPoseFile(std::string(LASERCELL_SOURCE_DIR) +
                                "/tests/registration/data/rs1_parasaurolophus_reference.txt");
}

/// RMS displacement of `points` between two poses, mm (the pose error tests use; the library's
/// PoseRmsDistanceMm).
inline double PoseRmsMm(const std::vector<Eigen::Vector3d>& points, const Eigen::Isometry3d& a,
                        const Eigen::Isometry3d& b) {
  return PoseRmsDistanceMm(points, a, b);
}

/// Rotation angle (rad) and translation distance (mm) between two poses within tolerances.
MATCHER_P3(PoseNear, expected, rot_tol_rad, trans_tol_mm, "") {
  const double rot = RotationDistance(arg, expected);
  const double trans = TranslationDistance(arg, expected);
  *result_listener << "rotation off by " << rot << " rad, translation by " << trans << " mm";
  return rot <= rot_tol_rad && trans <= trans_tol_mm;
}

/// A uniformly random rotation (random unit quaternion) and a translation in a cube of +-half_mm.
inline Eigen::Isometry3d RandomPose(std::mt19937_64& rng, double half_mm) {
  return datasets::RandomPose(rng, half_mm);
}

/// A small random rotation of exactly `angle_rad` about a random axis, then a translation of
/// exactly `trans_mm` in a random direction.
inline Eigen::Isometry3d RandomPerturbation(std::mt19937_64& rng, double angle_rad,
                                            double trans_mm) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Vector3d w{g(rng), g(rng), g(rng)}, t{g(rng), g(rng), g(rng)};
  return PoseFromRotationVector(w.normalized() * angle_rad, t.normalized() * trans_mm);
}

/// n points on a sphere with outward unit normals.
inline PointCloud SpherePoints(std::size_t n, double radius_mm, const Eigen::Vector3d& centre,
                               std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Draws<3>(g, rng).normalized();
    cloud.positions.push_back(centre + radius_mm * d);
    cloud.normals.push_back(d);
  }
  return cloud;
}

/// Points of the box [-half, half] surface, spacing ~step, with outward normals.
inline PointCloud BoxPoints(const Eigen::Vector3d& half, double step) {
  PointCloud cloud;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (double sign : {-1.0, 1.0}) {
      for (double a = -half(u); a <= half(u) + 1e-9; a += step) {
        for (double b = -half(v); b <= half(v) + 1e-9; b += step) {
          Eigen::Vector3d p, n = Eigen::Vector3d::Zero();
          p(axis) = sign * half(axis);
          p(u) = a;
          p(v) = b;
          n(axis) = sign;
          cloud.positions.push_back(p);
          cloud.normals.push_back(n);
        }
      }
    }
  }
  return cloud;
}

/// Simulated single view of `cloud` from `viewpoint`: front-facing points that are nearest to the
/// sensor in an orthographic grid of `cell_mm` cells (within `depth_tol_mm` of the front), plus
/// Gaussian noise of sigma `noise_mm` along the line of sight. Normals are kept (exact).
inline PointCloud SimulateView(const PointCloud& cloud, const Viewpoint& viewpoint, double cell_mm,
                               double depth_tol_mm, double noise_mm, std::mt19937_64& rng) {
  const Eigen::Vector3d centre = cloud.Centroid();
  const Eigen::Vector3d view = -viewpoint.TowardSensor(centre);
  const Eigen::Vector3d e1 = view.unitOrthogonal(), e2 = view.cross(e1);
  std::map<std::pair<long, long>, double> front;
  auto key = [&](const Eigen::Vector3d& p) {
    return std::make_pair(std::lround(std::floor((p - centre).dot(e1) / cell_mm)),
                          std::lround(std::floor((p - centre).dot(e2) / cell_mm)));
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.normals[i].dot(view) >= 0.0) continue;
    const double depth = (cloud.positions[i] - centre).dot(view);
    auto [it, inserted] = front.emplace(key(cloud.positions[i]), depth);
    if (!inserted) it->second = std::min(it->second, depth);
  }
  std::normal_distribution<double> g(0.0, noise_mm);
  PointCloud out;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.normals[i].dot(view) >= 0.0) continue;
    const double depth = (cloud.positions[i] - centre).dot(view);
    if (depth > front.at(key(cloud.positions[i])) + depth_tol_mm) continue;
    out.positions.push_back(cloud.positions[i] + (noise_mm > 0.0 ? g(rng) : 0.0) * view);
    out.normals.push_back(cloud.normals[i].normalized());
  }
  return out;
}

// The synthetic rs1 scenes come from datasets/synthetic_scan.hpp (shared with
// `lasercell bench robustness`); these wrappers cache the real inputs per test binary.

/// rs1 with the real parasaurolophus cut out: scene points within `margin_mm` of the model
/// posed at the reference pose are dropped. Real clutter (the other UWA objects) remains.
inline PointCloud Rs1WithoutParasaurolophus(double margin_mm = 8.0) {
  return datasets::CutOutModel(*UwaScene(), UwaModel()->Transformed(Rs1ReferencePose()), margin_mm);
}

/// The UWA parasaurolophus mesh sampled uniformly at about rs1's density (one point per
/// 0.5 mm^2, normals interpolated from the vertex normals, seed 99), cached.
inline const PointCloud& UwaModelDenseSurface() {
  static const PointCloud cloud = datasets::SampleMeshSurface(
      io::ReadPlyMesh(RealDataFile("uwa", "parasaurolophus_6700.ply")), 0.5, 99);
  return cloud;
}

/// Perspective z-buffer from the origin: per angular cell (cell_mm at 600 mm), the points within
/// depth_tol_mm of the nearest; back faces (normal away from the sensor) are dropped.
inline std::vector<std::size_t> VisibleFromOrigin(const PointCloud& cloud, double cell_mm,
                                                  double depth_tol_mm) {
  return datasets::VisibleFromOrigin(cloud, cell_mm, depth_tol_mm);
}

/// A synthetic rs1-like scan (datasets::RenderSyntheticScan): the real rs1 clutter
/// (parasaurolophus removed) plus the model's dense surface at each pose of `scene_from_model`,
/// with Gaussian noise `noise_mm` along the line of sight, occlusions resolved by a z-buffer from
/// the origin (the scanner). The part's normals are re-estimated from its noisy visible points
/// (k = 12); the clutter keeps rs1's normals. `part_points` (optional) receives how many points
/// of the part are visible.
inline PointCloud SyntheticRs1Scan(const std::vector<Eigen::Isometry3d>& scene_from_model,
                                   double noise_mm, std::mt19937_64& rng,
                                   std::size_t* part_points = nullptr) {
  static const PointCloud clutter = [] {
    PointCloud c = Rs1WithoutParasaurolophus();
    for (auto& n : c.normals) n.normalize();
    return c;
  }();
  datasets::SyntheticScanOptions options;
  options.noise_sigma_mm = noise_mm;
  datasets::SyntheticScan scan = datasets::RenderSyntheticScan(clutter, UwaModelDenseSurface(),
                                                               scene_from_model, options, rng);
  if (part_points) *part_points = scan.part_points;
  return std::move(scan.cloud);
}

/// A random placement of a model (frame `model`, centroid `model_centroid`) in rs1's field of
/// view: uniform random rotation, centroid within the scene's x/y footprint at its depth.
inline Eigen::Isometry3d RandomPlacementInRs1(const Eigen::Vector3d& model_centroid,
                                              std::mt19937_64& rng) {
  return datasets::RandomPlacementInRs1(model_centroid, rng);
}

}  // namespace lasercell::registration::test
