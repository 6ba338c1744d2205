#include "datasets/synthetic_scan.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unordered_map>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/random.hpp"
#include "core/se3.hpp"
#include "registration/kdtree.hpp"
#include "registration/normals.hpp"

namespace lasercell::datasets {

void SyntheticScanOptions::Check() const {
  auto non_negative = [](const char* field, double v) {
    if (!(v >= 0.0) || !std::isfinite(v))
      throw OptionError(std::string("SyntheticScanOptions.") + field + " = " + std::to_string(v) +
                        ": must be >= 0 mm");
  };
  auto positive = [](const char* field, double v) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw OptionError(std::string("SyntheticScanOptions.") + field + " = " + std::to_string(v) +
                        ": must be > 0 mm");
  };
  non_negative("noise_sigma_mm", noise_sigma_mm);
  non_negative("clutter_noise_sigma_mm", clutter_noise_sigma_mm);
  positive("zbuffer_cell_mm", zbuffer_cell_mm);
  positive("zbuffer_reference_range_mm", zbuffer_reference_range_mm);
  positive("zbuffer_depth_tolerance_mm", zbuffer_depth_tolerance_mm);
  if (part_normal_neighbors < 3)
    throw OptionError("SyntheticScanOptions.part_normal_neighbors must be >= 3");
}

Eigen::Isometry3d ReadPoseFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot open the pose file");
  std::string line, numbers;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') numbers += line + " ";
  }
  std::istringstream s(numbers);
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) s >> m(r, c);
  }
  if (!s) throw InputError(path + ": expected 16 numbers (a 4x4 row-major pose)");
  Eigen::Isometry3d pose;
  pose.matrix() = m;
  return pose;
}

void WritePoseFile(const std::string& path, const Eigen::Isometry3d& pose,
                   const std::string& comment) {
  std::ostringstream s;
  std::istringstream lines(comment);
  std::string line;
  while (std::getline(lines, line)) s << "# " << line << "\n";
  s.precision(10);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) s << (c > 0 ? " " : "") << pose.matrix()(r, c);
    s << "\n";
  }
  io::WriteFileAtomically(path, s.str());
}

PointCloud SampleMeshSurface(const TriangleMesh& mesh, double area_per_point_mm2,
                             std::uint64_t seed) {
  if (!(area_per_point_mm2 > 0.0))
    throw InputError("SampleMeshSurface: area_per_point_mm2 must be > 0");
  const auto& v = mesh.vertices;
  if (v.normals.size() != v.positions.size())
    throw InputError("SampleMeshSurface: the mesh has no vertex normals");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud out;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d a = v.positions[f(0)], b = v.positions[f(1)], c = v.positions[f(2)];
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const double expected = area / area_per_point_mm2;
    auto count = static_cast<int>(expected);
    if (u(rng) < expected - count) ++count;  // stochastic rounding keeps the density unbiased
    for (int k = 0; k < count; ++k) {
      double s = u(rng), t = u(rng);
      if (s + t > 1.0) s = 1.0 - s, t = 1.0 - t;  // fold the square onto the triangle
      out.positions.push_back(a + s * (b - a) + t * (c - a));
      out.normals.push_back(((1 - s - t) * v.normals[f(0)].normalized() +
                             s * v.normals[f(1)].normalized() + t * v.normals[f(2)].normalized())
                                .normalized());
    }
  }
  return out;
}

PointCloud CutOutModel(const PointCloud& scene, const PointCloud& posed_model, double margin_mm) {
  const registration::KdTree tree(posed_model.positions);
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    registration::Neighbor nn;
    tree.Nearest(scene.positions[i], &nn);
    if (nn.distance_sq > margin_mm * margin_mm) keep.push_back(i);
  }
  return scene.Subset(keep);
}

std::vector<std::size_t> VisibleFromOrigin(const PointCloud& cloud, double cell_mm,
                                           double depth_tolerance_mm, double reference_range_mm) {
  if (cloud.normals.size() != cloud.positions.size())
    throw InputError("VisibleFromOrigin: the cloud needs normals");
  const double scale = reference_range_mm / cell_mm;
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
    if (cloud.normals[i].dot(-p) > 0.0 && p.norm() <= front.at(key(p)) + depth_tolerance_mm)
      visible.push_back(i);
  }
  return visible;
}

SyntheticScan RenderSyntheticScan(const PointCloud& clutter, const PointCloud& part_surface,
                                  const std::vector<Eigen::Isometry3d>& scene_from_model,
                                  const SyntheticScanOptions& options, std::mt19937_64& rng) {
  options.Check();
  if (clutter.normals.size() != clutter.positions.size() ||
      part_surface.normals.size() != part_surface.positions.size())
    throw InputError("RenderSyntheticScan: clutter and part surface need normals");
  PointCloud part;
  for (const Eigen::Isometry3d& pose : scene_from_model)
    part.Append(part_surface.Transformed(pose));
  // The scanner measures range: noise along the line of sight (the sensor is at the origin).
  if (options.noise_sigma_mm > 0.0) {
    std::normal_distribution<double> g(0.0, options.noise_sigma_mm);
    for (auto& p : part.positions) p += g(rng) * p.normalized();
  }
  PointCloud noisy_clutter;
  const PointCloud* clutter_used = &clutter;
  if (options.clutter_noise_sigma_mm > 0.0) {
    noisy_clutter = clutter;
    std::normal_distribution<double> g(0.0, options.clutter_noise_sigma_mm);
    for (auto& p : noisy_clutter.positions) p += g(rng) * p.normalized();
    clutter_used = &noisy_clutter;
  }
  PointCloud combined = *clutter_used;
  if (!part.empty()) combined.Append(part);
  const std::size_t n_clutter = clutter_used->size();
  std::vector<std::size_t> visible_clutter, visible_part;
  for (std::size_t i :
       VisibleFromOrigin(combined, options.zbuffer_cell_mm, options.zbuffer_depth_tolerance_mm,
                         options.zbuffer_reference_range_mm)) {
    if (i < n_clutter) {
      visible_clutter.push_back(i);
    } else {
      visible_part.push_back(i - n_clutter);
    }
  }
  SyntheticScan scan;
  scan.cloud = clutter_used->Subset(visible_clutter);
  scan.clutter_points = visible_clutter.size();
  scan.part_points = visible_part.size();
  if (!visible_part.empty()) {
    PointCloud seen = part.Subset(visible_part);
    seen.normals.clear();
    registration::NormalOptions normals;  // viewpoint: the origin, the scanner
    normals.k = options.part_normal_neighbors;
    normals.threads = 1;
    scan.cloud.Append(registration::WithEstimatedNormals(seen, normals));
  }
  return scan;
}

SyntheticScan RenderSyntheticScan(const PointCloud& clutter, const PointCloud& part_surface,
                                  const std::vector<Eigen::Isometry3d>& scene_from_model,
                                  const SyntheticScanOptions& options) {
  std::mt19937_64 rng(options.seed);
  return RenderSyntheticScan(clutter, part_surface, scene_from_model, options, rng);
}

Eigen::Isometry3d RandomPose(std::mt19937_64& rng, double half_mm) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-half_mm, half_mm);
  Eigen::Quaterniond q{g(rng), g(rng), g(rng),
                       g(rng)};  // normalized Gaussian 4-vector: uniform on SO(3)
  q.normalize();
  return PoseFromQuaternion(q, Draws<3>(u, rng));
}

Eigen::Isometry3d RandomPlacementInRs1(const Eigen::Vector3d& model_centroid,
                                       std::mt19937_64& rng) {
  std::uniform_real_distribution<double> x(-110.0, 70.0), y(-90.0, 90.0), z(-640.0, -600.0);
  Eigen::Isometry3d pose = RandomPose(rng, 0.0);
  pose.translation() = Eigen::Vector3d{x(rng), y(rng), z(rng)} - pose.linear() * model_centroid;
  return pose;
}

Rs1SyntheticData LoadRs1SyntheticData(const std::string& uwa_dir,
                                      const std::string& reference_pose_file) {
  const std::string model_path = uwa_dir + "/parasaurolophus_6700.ply";
  const std::string scene_path = uwa_dir + "/rs1_normals.bin.ply";
  for (const std::string& path : {model_path, scene_path, reference_pose_file}) {
    if (!std::filesystem::is_regular_file(path))
      throw FileError(path, "not found (bundled in datasets/real/uwa)");
  }
  Rs1SyntheticData data;
  data.model = io::ReadPointCloud(model_path);
  data.reference_scene_from_model = ReadPoseFile(reference_pose_file);
  data.part_surface = SampleMeshSurface(io::ReadPlyMesh(model_path), 0.5, 99);
  data.clutter = CutOutModel(io::ReadPointCloud(scene_path),
                             data.model.Transformed(data.reference_scene_from_model), 8.0);
  for (auto& n : data.clutter.normals) n.normalize();
  return data;
}

}  // namespace lasercell::datasets
