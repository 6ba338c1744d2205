#pragma once
// Helpers shared by the registration tests: real UWA data (cached per test binary), seeded
// synthetic shapes with exact normals, random poses, a simulated single-view scan, pose
// comparison by model-point displacement, and the committed rs1 reference pose.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <unordered_map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/point_cloud.hpp"
#include "core/se3.hpp"
#include "registration/kdtree.hpp"
#include "registration/normals.hpp"
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

#define LASERCELL_REQUIRE_UWA()                                                            \
  if (::lasercell::registration::test::UwaModel() == nullptr ||                            \
      ::lasercell::registration::test::UwaScene() == nullptr)                              \
  GTEST_FAIL() << "bundled UWA data (parasaurolophus_6700.ply, rs1_normals.bin.ply) missing " \
                  "from datasets/real/uwa"

/// The committed reference pose scene_from_model of the parasaurolophus in rs1.
inline Eigen::Isometry3d Rs1ReferencePose() {
  std::ifstream in(std::string(LASERCELL_SOURCE_DIR) + "/tests/registration/data/rs1_parasaurolophus_reference.txt");
  std::string line, numbers;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') numbers += line + " ";
  }
  std::istringstream s(numbers);
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) s >> m(r, c);
  }
  if (!s) throw InputError("rs1_parasaurolophus_reference.txt: expected 16 numbers");
  Eigen::Isometry3d pose;
  pose.matrix() = m;
  return pose;
}

/// RMS displacement of `points` between two poses, mm (the pose error tests use).
inline double PoseRmsMm(const std::vector<Eigen::Vector3d>& points, const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  double sum = 0.0;
  for (const auto& p : points) sum += (a * p - b * p).squaredNorm();
  return std::sqrt(sum / static_cast<double>(points.size()));
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
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-half_mm, half_mm);
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return PoseFromQuaternion(q, Eigen::Vector3d(u(rng), u(rng), u(rng)));
}

/// A small random rotation of exactly `angle_rad` about a random axis, then a translation of
/// exactly `trans_mm` in a random direction.
inline Eigen::Isometry3d RandomPerturbation(std::mt19937_64& rng, double angle_rad, double trans_mm) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Vector3d w(g(rng), g(rng), g(rng)), t(g(rng), g(rng), g(rng));
  return PoseFromRotationVector(w.normalized() * angle_rad, t.normalized() * trans_mm);
}

/// n points on a sphere with outward unit normals.
inline PointCloud SpherePoints(std::size_t n, double radius_mm, const Eigen::Vector3d& centre, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
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
inline PointCloud SimulateView(const PointCloud& cloud, const Viewpoint& viewpoint, double cell_mm, double depth_tol_mm,
                               double noise_mm, std::mt19937_64& rng) {
  const Eigen::Vector3d centre = cloud.Centroid();
  const Eigen::Vector3d view = -viewpoint.TowardSensor(centre);
  const Eigen::Vector3d e1 = view.unitOrthogonal(), e2 = view.cross(e1);
  std::map<std::pair<long, long>, double> front;
  auto key = [&](const Eigen::Vector3d& p) {
    return std::make_pair(std::lround(std::floor((p - centre).dot(e1) / cell_mm)), std::lround(std::floor((p - centre).dot(e2) / cell_mm)));
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

/// rs1 with the real parasaurolophus cut out: scene points within `margin_mm` of the model
/// posed at the reference pose are dropped. Real clutter (the other UWA objects) remains.
inline PointCloud Rs1WithoutParasaurolophus(double margin_mm = 8.0) {
  const PointCloud& scene = *UwaScene();
  const PointCloud posed = UwaModel()->Transformed(Rs1ReferencePose());
  const KdTree tree(posed.positions);
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    Neighbor nn;
    tree.Nearest(scene.positions[i], &nn);
    if (nn.distance_sq > margin_mm * margin_mm) keep.push_back(i);
  }
  return scene.Subset(keep);
}

/// The UWA parasaurolophus mesh sampled uniformly at about rs1's density (one point per
/// 0.5 mm^2, normals interpolated from the vertex normals), cached.
inline const PointCloud& UwaModelDenseSurface() {
  static const PointCloud cloud = [] {
    const TriangleMesh mesh = io::ReadPlyMesh(RealDataFile("uwa", "parasaurolophus_6700.ply"));
    std::mt19937_64 rng(99);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    PointCloud out;
    for (const Eigen::Vector3i& f : mesh.faces) {
      const auto& v = mesh.vertices;
      const Eigen::Vector3d a = v.positions[f(0)], b = v.positions[f(1)], c = v.positions[f(2)];
      const double area = 0.5 * (b - a).cross(c - a).norm();
      const double expected = area / 0.5;
      auto count = static_cast<int>(expected);
      if (u(rng) < expected - count) ++count;
      for (int k = 0; k < count; ++k) {
        double s = u(rng), t = u(rng);
        if (s + t > 1.0) s = 1.0 - s, t = 1.0 - t;
        out.positions.push_back(a + s * (b - a) + t * (c - a));
        out.normals.push_back(((1 - s - t) * v.normals[f(0)].normalized() + s * v.normals[f(1)].normalized() +
                               t * v.normals[f(2)].normalized()).normalized());
      }
    }
    return out;
  }();
  return cloud;
}

/// Perspective z-buffer from the origin: per angular cell (cell_mm at 600 mm), the points within
/// depth_tol_mm of the nearest; back faces (normal away from the sensor) are dropped.
inline std::vector<std::size_t> VisibleFromOrigin(const PointCloud& cloud, double cell_mm, double depth_tol_mm) {
  const double scale = 600.0 / cell_mm;
  auto key = [&](const Eigen::Vector3d& p) {
    const double depth = p.norm();
    return (static_cast<std::int64_t>(std::floor(p.x() / depth * scale)) << 32) ^
           static_cast<std::int64_t>(std::floor(p.y() / depth * scale) + (1LL << 30));
  };
  std::unordered_map<std::int64_t, double> front;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d& p = cloud.positions[i];
    if (cloud.normals[i].dot(-p) <= 0.0) continue;
    auto [it, inserted] = front.emplace(key(p), p.norm());
    if (!inserted) it->second = std::min(it->second, p.norm());
  }
  std::vector<std::size_t> visible;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d& p = cloud.positions[i];
    if (cloud.normals[i].dot(-p) > 0.0 && p.norm() <= front.at(key(p)) + depth_tol_mm) visible.push_back(i);
  }
  return visible;
}

/// A synthetic rs1-like scan: the real rs1 clutter (parasaurolophus removed) plus the model's
/// dense surface at each pose of `scene_from_model`, with Gaussian noise `noise_mm` along the line of sight,
/// occlusions resolved by a z-buffer from the origin (the scanner). The part's normals are
/// re-estimated from its noisy visible points (k = 12); the clutter keeps rs1's normals.
/// `part_points` (optional) receives how many points of the part are visible.
inline PointCloud SyntheticRs1Scan(const std::vector<Eigen::Isometry3d>& scene_from_model, double noise_mm,
                                   std::mt19937_64& rng, std::size_t* part_points = nullptr) {
  static const PointCloud clutter = [] {
    PointCloud c = Rs1WithoutParasaurolophus();
    for (auto& n : c.normals) n.normalize();
    return c;
  }();
  PointCloud part;
  for (const Eigen::Isometry3d& pose : scene_from_model) part.Append(UwaModelDenseSurface().Transformed(pose));
  std::normal_distribution<double> g(0.0, noise_mm);
  for (auto& p : part.positions) p += g(rng) * p.normalized();
  PointCloud combined = clutter;
  combined.Append(part);
  std::vector<std::size_t> visible_clutter, visible_part;
  for (std::size_t i : VisibleFromOrigin(combined, 0.8, 2.0)) (i < clutter.size() ? visible_clutter : visible_part).push_back(i - (i < clutter.size() ? 0 : clutter.size()));
  PointCloud scan = clutter.Subset(visible_clutter);
  PointCloud seen = part.Subset(visible_part);
  seen.normals.clear();
  NormalOptions normals;
  normals.threads = 1;
  scan.Append(WithEstimatedNormals(seen, normals));
  if (part_points) *part_points = visible_part.size();
  return scan;
}

/// A random placement of a model (frame `model`, centroid `model_centroid`) in rs1's field of
/// view: uniform random rotation, centroid within the scene's x/y footprint at its depth.
inline Eigen::Isometry3d RandomPlacementInRs1(const Eigen::Vector3d& model_centroid, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> x(-110.0, 70.0), y(-90.0, 90.0), z(-640.0, -600.0);
  Eigen::Isometry3d pose = RandomPose(rng, 0.0);
  pose.translation() = Eigen::Vector3d(x(rng), y(rng), z(rng)) - pose.linear() * model_centroid;
  return pose;
}

}  // namespace lasercell::registration::test
