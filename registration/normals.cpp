#include "registration/normals.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "registration/filters.hpp"
#include "registration/kdtree.hpp"

namespace lasercell::registration {
namespace {

// Fits a plane to `count` points given by accessor(i). Returns false when degenerate.
template <typename Accessor>
bool FitPlane(std::size_t count, const Accessor& point, Eigen::Vector3d* normal, float* curvature) {
  if (count < 3) return false;
  // Covariance around the mean, accumulated relative to the first point for numerical safety
  // far from the origin.
  const Eigen::Vector3d origin = point(0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum_sq = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3d d = point(i) - origin;
    sum += d;
    sum_sq.noalias() += d * d.transpose();
  }
  const Eigen::Vector3d mean = sum / static_cast<double>(count);
  const Eigen::Matrix3d cov = sum_sq / static_cast<double>(count) - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(cov);
  const Eigen::Vector3d eig = solver.eigenvalues();  // ascending
  const double total = eig.sum();
  // A line or a single point has no plane. The closed-form solver's error on a double (zero)
  // eigenvalue is ~sqrt(eps) relative, hence the 1e-6 threshold (spread ratio 1e-3).
  if (!(total > 0.0) || !(eig(1) > 1e-6 * total)) return false;
  *normal = solver.eigenvectors().col(0).normalized();
  *curvature = static_cast<float>(std::max(0.0, eig(0)) / total);
  return normal->allFinite();
}

}  // namespace

void NormalOptions::Check() const {
  if (k < 3)
    throw OptionError("NormalOptions.k = " + std::to_string(k) + ": must be >= 3 neighbours");
  if (!(radius_mm >= 0.0) || !std::isfinite(radius_mm)) {
    throw OptionError("NormalOptions.radius_mm = " + std::to_string(radius_mm) +
                      ": must be >= 0 mm (0 selects the k nearest neighbours)");
  }
  if (grid_window < 1 || grid_window > 16) {
    throw OptionError("NormalOptions.grid_window = " + std::to_string(grid_window) +
                      ": must be in [1, 16] cells");
  }
  if (!(grid_max_distance_mm >= 0.0)) {
    throw OptionError("NormalOptions.grid_max_distance_mm must be >= 0 mm (0 = no limit)");
  }
  if (min_neighbors < 3) throw OptionError("NormalOptions.min_neighbors must be >= 3");
  viewpoint.Check("NormalOptions.viewpoint");
}

namespace {

// The normals of the points at[0 .. count) of `cloud` (every point when `at` is null), each from
// its neighbourhood in the whole cloud; slot k of the result is point at[k].
NormalEstimationResult EstimateNormalsOf(const PointCloud& cloud, const NormalOptions& options,
                                         std::span<const Eigen::Vector3d> line_of_sight,
                                         const std::size_t* at, std::size_t count) {
  options.Check();
  cloud.Validate("EstimateNormals input");
  const std::size_t n = cloud.size();
  if (!line_of_sight.empty() && line_of_sight.size() != n) {
    throw InputError("EstimateNormals: line_of_sight has " + std::to_string(line_of_sight.size()) +
                     " vectors for " + std::to_string(n) + " points; give one per point or none");
  }
  for (std::size_t k = 0; at != nullptr && k < count; ++k) {
    if (at[k] >= n) {
      throw InputError("EstimateNormalsAt: index " + std::to_string(at[k]) + " for a cloud of " +
                       std::to_string(n) + " points");
    }
  }
  NormalEstimationResult result;
  result.normals.assign(count, Eigen::Vector3d::Zero());
  result.valid.assign(count, 0);
  result.curvature.assign(count, 0.0F);
  result.used_grid = options.use_grid_when_organized && cloud.IsOrganized();

  KdTree tree;
  std::vector<std::int32_t> cell;
  const std::size_t cols = static_cast<std::size_t>(std::max(cloud.grid_cols, 0));
  if (result.used_grid) {
    cell.assign(static_cast<std::size_t>(cloud.grid_rows) * cols, -1);
    for (std::size_t i = 0; i < n; ++i) {
      cell[static_cast<std::size_t>(cloud.profile[i]) * cols +
           static_cast<std::size_t>(cloud.column[i])] = static_cast<std::int32_t>(i);
    }
  } else {
    tree = KdTree(cloud.positions);
  }
  const double max_d_sq = options.grid_max_distance_mm > 0.0
                              ? options.grid_max_distance_mm * options.grid_max_distance_mm
                              : std::numeric_limits<double>::infinity();

  // Each point's fit only reads the cloud and writes its own slot: thread-count independent.
  ParallelForChunks(options.threads, count, 512, [&](std::size_t begin, std::size_t end) {
    std::vector<Neighbor> hits;
    std::vector<std::uint32_t> grid_hits;
    for (std::size_t slot = begin; slot < end; ++slot) {
      const std::size_t i = at == nullptr ? slot : at[slot];
      const Eigen::Vector3d& p = cloud.positions[i];
      Eigen::Vector3d normal;
      float curvature = 0.0F;
      bool ok = false;
      if (result.used_grid) {
        grid_hits.clear();
        const int w = options.grid_window;
        for (int r = cloud.profile[i] - w; r <= cloud.profile[i] + w; ++r) {
          if (r < 0 || r >= cloud.grid_rows) continue;
          for (int c = cloud.column[i] - w; c <= cloud.column[i] + w; ++c) {
            if (c < 0 || c >= cloud.grid_cols) continue;
            const std::int32_t j =
                cell[static_cast<std::size_t>(r) * cols + static_cast<std::size_t>(c)];
            if (j >= 0 &&
                (cloud.positions[static_cast<std::size_t>(j)] - p).squaredNorm() <= max_d_sq) {
              grid_hits.push_back(static_cast<std::uint32_t>(j));
            }
          }
        }
        if (grid_hits.size() >= options.min_neighbors) {
          ok = FitPlane(
              grid_hits.size(), [&](std::size_t m) { return cloud.positions[grid_hits[m]]; },
              &normal, &curvature);
        }
      } else {
        if (options.radius_mm > 0.0)
          tree.RadiusSearch(p, options.radius_mm, &hits);
        else
          tree.KNearest(p, options.k, &hits);
        if (hits.size() >= options.min_neighbors) {
          ok = FitPlane(
              hits.size(), [&](std::size_t m) { return cloud.positions[hits[m].index]; }, &normal,
              &curvature);
        }
      }
      if (!ok) continue;
      const Eigen::Vector3d toward = line_of_sight.empty() ? options.viewpoint.TowardSensor(p)
                                                           : Eigen::Vector3d(line_of_sight[i]);
      if (normal.dot(toward) < 0.0) normal = -normal;
      result.normals[slot] = normal;
      result.valid[slot] = 1;
      result.curvature[slot] = curvature;
    }
  });
  for (std::uint8_t v : result.valid) result.invalid_count += v ? 0 : 1;
  return result;
}

}  // namespace

NormalEstimationResult EstimateNormals(const PointCloud& cloud, const NormalOptions& options,
                                       std::span<const Eigen::Vector3d> line_of_sight) {
  return EstimateNormalsOf(cloud, options, line_of_sight, nullptr, cloud.size());
}

NormalEstimationResult EstimateNormalsAt(const PointCloud& cloud, std::span<const std::size_t> at,
                                         const NormalOptions& options,
                                         std::span<const Eigen::Vector3d> line_of_sight) {
  return EstimateNormalsOf(cloud, options, line_of_sight, at.data(), at.size());
}

CloudWithNormals WithNormalsAtCells(const PointCloud& cloud, double cell_mm,
                                    const NormalOptions& options,
                                    std::span<const Eigen::Vector3d> line_of_sight) {
  std::vector<std::size_t> at;
  if (cell_mm > 0.0) at = OnePerCellIndices(cloud.positions, cell_mm, CellPoint::kNearestCentre);
  NormalEstimationResult fit = cell_mm > 0.0 ? EstimateNormalsAt(cloud, at, options, line_of_sight)
                                             : EstimateNormals(cloud, options, line_of_sight);
  CloudWithNormals out;
  out.kept.reserve(fit.valid.size());
  std::vector<Eigen::Vector3d> normals;
  normals.reserve(fit.valid.size());
  for (std::size_t k = 0; k < fit.valid.size(); ++k) {
    if (!fit.valid[k]) continue;
    out.kept.push_back(cell_mm > 0.0 ? at[k] : k);
    normals.push_back(fit.normals[k]);
  }
  out.dropped = fit.invalid_count;
  out.cloud = cloud.Subset(out.kept);
  out.cloud.normals = std::move(normals);
  return out;
}

PointCloud WithEstimatedNormals(const PointCloud& cloud, const NormalOptions& options,
                                std::size_t* dropped) {
  CloudWithNormals out = WithNormalsAtCells(cloud, 0.0, options);
  if (dropped) *dropped = out.dropped;
  return std::move(out.cloud);
}

std::vector<Eigen::Vector3d> MeshVertexNormals(const TriangleMesh& mesh) {
  if (mesh.faces.empty()) {
    throw InputError(
        "mesh normals: the mesh has no faces; give a PLY mesh with faces, or a cloud "
        "with normals");
  }
  const std::size_t n = mesh.vertices.size();
  std::vector<Eigen::Vector3d> normals(n, Eigen::Vector3d::Zero());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= n) {
        throw InputError("mesh normals: face " + std::to_string(f) + " uses vertex " +
                         std::to_string(t[k]) + ", but the mesh has " + std::to_string(n) +
                         " vertices");
      }
    }
    const Eigen::Vector3d& a = mesh.vertices.positions[t[0]];
    // Twice the face's area along its normal: larger faces weigh more.
    const Eigen::Vector3d area_normal =
        (mesh.vertices.positions[t[1]] - a).cross(mesh.vertices.positions[t[2]] - a);
    for (int k = 0; k < 3; ++k) normals[t[k]] += area_normal;
  }
  for (Eigen::Vector3d& v : normals) {
    const double length = v.norm();
    v = length > 1e-12 ? Eigen::Vector3d(v / length) : Eigen::Vector3d::Zero();
  }
  return normals;
}

PointCloud WithMeshNormals(const TriangleMesh& mesh, std::size_t* dropped) {
  std::vector<Eigen::Vector3d> normals = MeshVertexNormals(mesh);
  std::vector<std::size_t> keep;
  keep.reserve(normals.size());
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!normals[i].isZero()) keep.push_back(i);
  }
  PointCloud out = mesh.vertices;
  out.normals = std::move(normals);
  if (dropped) *dropped = out.size() - keep.size();
  if (keep.size() == out.size()) return out;
  return out.Subset(keep);
}

void OrientNormalsTowardViewpoint(PointCloud* cloud, const Viewpoint& viewpoint) {
  LASERCELL_CHECK(cloud->normals.size() == cloud->positions.size(),
                  "OrientNormalsTowardViewpoint needs one normal per point");
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    if (cloud->normals[i].dot(viewpoint.TowardSensor(cloud->positions[i])) < 0.0) {
      cloud->normals[i] = -cloud->normals[i];
    }
  }
}

}  // namespace lasercell::registration
