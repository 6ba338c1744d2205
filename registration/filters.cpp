#include "registration/filters.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>
#include <unordered_map>

#include "core/error.hpp"
#include "registration/kdtree.hpp"

namespace lasercell::registration {
namespace {

// Union-find whose root is always the smallest index of the set, so labels do not depend on
// the order in which unions happen.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0U);
  }
  std::uint32_t Find(std::uint32_t i) {
    while (parent_[i] != i) {
      parent_[i] = parent_[parent_[i]];
      i = parent_[i];
    }
    return i;
  }
  void Union(std::uint32_t a, std::uint32_t b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return;
    if (a < b)
      parent_[b] = a;
    else
      parent_[a] = b;
  }

 private:
  std::vector<std::uint32_t> parent_;
};

// Open-addressing hash from a packed voxel key to a dense voxel id (first-hit order).
class VoxelIdMap {
 public:
  explicit VoxelIdMap(std::size_t expected) {
    std::size_t capacity = 16;
    while (capacity < 2 * expected) capacity *= 2;
    keys_.assign(capacity, kEmpty);
    ids_.resize(capacity);
    mask_ = capacity - 1;
  }
  // Returns the id of `key`, inserting it with `next_id` when new (then *inserted = true).
  std::uint32_t FindOrInsert(std::uint64_t key, std::uint32_t next_id, bool* inserted) {
    std::size_t slot = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> 20) & mask_;
    while (true) {
      if (keys_[slot] == key) {
        *inserted = false;
        return ids_[slot];
      }
      if (keys_[slot] == kEmpty) {
        keys_[slot] = key;
        ids_[slot] = next_id;
        *inserted = true;
        return next_id;
      }
      slot = (slot + 1) & mask_;
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> ids_;
  std::size_t mask_ = 0;
};

ClusterFilterResult LabelComponents(DisjointSets& sets, std::size_t n, std::size_t min_size) {
  ClusterFilterResult result;
  result.labels.assign(n, -1);
  std::vector<std::int32_t> label_of_root(n, -1);
  std::vector<std::size_t> sizes;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t root = sets.Find(static_cast<std::uint32_t>(i));
    if (label_of_root[root] < 0) {
      label_of_root[root] = static_cast<std::int32_t>(sizes.size());
      sizes.push_back(0);
    }
    result.labels[i] = label_of_root[root];
    ++sizes[static_cast<std::size_t>(result.labels[i])];
  }
  result.components = sizes.size();
  for (std::size_t s : sizes) result.removed_components += s < min_size ? 1 : 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (sizes[static_cast<std::size_t>(result.labels[i])] >= min_size) result.kept.push_back(i);
  }
  return result;
}

}  // namespace

std::vector<std::size_t> CropBoxIndices(const PointCloud& cloud, const BoundingBox& box_in_frame,
                                        const Eigen::Isometry3d& frame_from_cloud) {
  std::vector<std::size_t> inside;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (box_in_frame.Contains(frame_from_cloud * cloud.positions[i])) inside.push_back(i);
  }
  return inside;
}

PointCloud CropBox(const PointCloud& cloud, const BoundingBox& box_in_frame,
                   const Eigen::Isometry3d& frame_from_cloud) {
  const auto inside = CropBoxIndices(cloud, box_in_frame, frame_from_cloud);
  return cloud.Subset(inside);
}

void ClusterFilterOptions::Check() const {
  if (!(radius_mm > 0.0) || !std::isfinite(radius_mm)) {
    throw OptionError("ClusterFilterOptions.radius_mm = " + std::to_string(radius_mm) +
                      ": must be a positive distance in mm (about 2-3x the point spacing)");
  }
  if (min_cluster_size < 1) {
    throw OptionError("ClusterFilterOptions.min_cluster_size must be >= 1");
  }
  if (grid_window < 1 || grid_window > 16) {
    throw OptionError("ClusterFilterOptions.grid_window = " + std::to_string(grid_window) +
                      ": must be in [1, 16] cells");
  }
}

ClusterFilterResult RemoveSmallClusters(const PointCloud& cloud,
                                        const ClusterFilterOptions& options) {
  options.Check();
  const std::size_t n = cloud.size();
  DisjointSets sets(n);
  const double radius_sq = options.radius_mm * options.radius_mm;
  const bool use_grid = options.use_grid_when_organized && cloud.IsOrganized();
  if (use_grid) {
    // Skotheim IV-A on a sweep: neighbours are found through the profile/column grid.
    const std::size_t rows = static_cast<std::size_t>(cloud.grid_rows);
    const std::size_t cols = static_cast<std::size_t>(cloud.grid_cols);
    std::vector<std::int32_t> cell(rows * cols, -1);
    for (std::size_t i = 0; i < n; ++i) {
      cell[static_cast<std::size_t>(cloud.profile[i]) * cols +
           static_cast<std::size_t>(cloud.column[i])] = static_cast<std::int32_t>(i);
    }
    const int w = options.grid_window;
    for (std::size_t i = 0; i < n; ++i) {
      const int r0 = cloud.profile[i];
      const int c0 = cloud.column[i];
      // Forward half of the window only: each unordered pair is visited once.
      for (int dr = 0; dr <= w; ++dr) {
        for (int dc = -w; dc <= w; ++dc) {
          if (dr == 0 && dc <= 0) continue;
          const int r = r0 + dr;
          const int c = c0 + dc;
          if (r >= cloud.grid_rows || c < 0 || c >= cloud.grid_cols) continue;
          const std::int32_t j =
              cell[static_cast<std::size_t>(r) * cols + static_cast<std::size_t>(c)];
          if (j < 0) continue;
          if ((cloud.positions[i] - cloud.positions[static_cast<std::size_t>(j)]).squaredNorm() <=
              radius_sq) {
            sets.Union(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
          }
        }
      }
    }
  } else {
    const KdTree tree(cloud.positions);
    std::vector<Neighbor> hits;
    for (std::size_t i = 0; i < n; ++i) {
      tree.RadiusSearch(cloud.positions[i], options.radius_mm, &hits);
      for (const Neighbor& h : hits) {
        if (h.index > i) sets.Union(static_cast<std::uint32_t>(i), h.index);
      }
    }
  }
  ClusterFilterResult result = LabelComponents(sets, n, options.min_cluster_size);
  result.used_grid = use_grid;
  return result;
}

void VoxelGridOptions::Check() const {
  if (!(voxel_size_mm > 0.0) || !std::isfinite(voxel_size_mm)) {
    throw OptionError("VoxelGridOptions.voxel_size_mm = " + std::to_string(voxel_size_mm) +
                      ": must be a positive voxel edge in mm");
  }
  if (!(min_normal_coherence >= 0.0 && min_normal_coherence <= 1.0)) {
    throw OptionError("VoxelGridOptions.min_normal_coherence = " +
                      std::to_string(min_normal_coherence) + ": must be in [0, 1]");
  }
  if (min_points_per_voxel < 1) {
    throw OptionError("VoxelGridOptions.min_points_per_voxel must be >= 1");
  }
  if (!(normal_split_angle_rad >= 0.0 && normal_split_angle_rad <= std::numbers::pi)) {
    throw OptionError("VoxelGridOptions.normal_split_angle_rad = " +
                      std::to_string(normal_split_angle_rad) + ": must be in [0, pi] rad");
  }
}

PointCloud VoxelGridDownsample(const PointCloud& cloud, const VoxelGridOptions& options,
                               std::vector<std::int32_t>* voxel_of_point) {
  options.Check();
  PointCloud out;
  const std::size_t n = cloud.size();
  if (voxel_of_point) voxel_of_point->assign(n, -1);
  if (n == 0) return out;
  const BoundingBox bounds = cloud.Bounds();
  const Eigen::Vector3d extent = bounds.Size() / options.voxel_size_mm;
  constexpr double kMaxCells = double{1 << 21};  // 21 bits per axis in the packed key
  if (!(extent.maxCoeff() < kMaxCells - 1)) {
    throw OptionError("VoxelGridOptions.voxel_size_mm = " + std::to_string(options.voxel_size_mm) +
                      ": too small for a cloud " + std::to_string(bounds.Size().maxCoeff()) +
                      " mm across (more than 2^21 voxels per axis); use a larger voxel");
  }
  const double inv = 1.0 / options.voxel_size_mm;
  VoxelIdMap map(std::min<std::size_t>(n, 1 << 22));
  std::vector<std::uint32_t> voxel(n);
  std::vector<Eigen::Vector3d> sum_p;
  std::vector<Eigen::Vector3d> sum_n;
  std::vector<std::uint32_t> count;
  const bool has_normals = cloud.HasNormals() && options.normal_mode != VoxelNormalMode::kNone;
  // Samples of one voxel split by normal: a chain from the voxel's first sample, each link with
  // the normal of the point that started it.
  const bool split = cloud.HasNormals() && options.normal_split_angle_rad > 0.0;
  const double split_cos = std::cos(options.normal_split_angle_rad);
  std::vector<std::int32_t> next_sample;
  std::vector<Eigen::Vector3d> first_normal;
  const auto add_sample = [&](std::size_t point) {
    sum_p.push_back(Eigen::Vector3d::Zero());
    sum_n.push_back(Eigen::Vector3d::Zero());
    count.push_back(0);
    if (split) {
      next_sample.push_back(-1);
      first_normal.push_back(cloud.normals[point]);
    }
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d c = ((cloud.positions[i] - bounds.min) * inv).array().floor();
    const std::uint64_t key = (static_cast<std::uint64_t>(c.x()) << 42) |
                              (static_cast<std::uint64_t>(c.y()) << 21) |
                              static_cast<std::uint64_t>(c.z());
    bool inserted = false;
    std::uint32_t id = map.FindOrInsert(key, static_cast<std::uint32_t>(count.size()), &inserted);
    if (inserted) add_sample(i);
    if (split && !inserted) {
      while (cloud.normals[i].dot(first_normal[id]) < split_cos) {
        if (next_sample[id] < 0) {
          next_sample[id] = static_cast<std::int32_t>(count.size());
          add_sample(i);
        }
        id = static_cast<std::uint32_t>(next_sample[id]);
      }
    }
    voxel[i] = id;
    sum_p[id] += cloud.positions[i];
    if (has_normals) sum_n[id] += cloud.normals[i];
    ++count[id];
  }
  const std::size_t voxels = count.size();
  std::vector<Eigen::Vector3d> centroid(voxels);
  for (std::size_t v = 0; v < voxels; ++v) centroid[v] = sum_p[v] / count[v];

  std::vector<Eigen::Vector3d> normal(has_normals ? voxels : 0);
  std::vector<bool> keep(voxels, true);
  for (std::size_t v = 0; v < voxels; ++v) keep[v] = count[v] >= options.min_points_per_voxel;
  if (has_normals && options.normal_mode == VoxelNormalMode::kAverage) {
    for (std::size_t v = 0; v < voxels; ++v) {
      const double length = sum_n[v].norm();
      if (length / count[v] < options.min_normal_coherence || length == 0.0)
        keep[v] = false;
      else
        normal[v] = sum_n[v] / length;
    }
  } else if (has_normals) {
    // Carry the dense normal of the point nearest the centroid (seed: normals are estimated on
    // the dense cloud before subsampling).
    std::vector<double> best(voxels, std::numeric_limits<double>::max());
    for (std::size_t i = 0; i < n; ++i) {
      const double d = (cloud.positions[i] - centroid[voxel[i]]).squaredNorm();
      if (d < best[voxel[i]]) {
        best[voxel[i]] = d;
        normal[voxel[i]] = cloud.normals[i];
      }
    }
  }
  std::vector<std::int32_t> output_index(voxels, -1);
  out.Reserve(voxels);
  for (std::size_t v = 0; v < voxels; ++v) {
    if (!keep[v]) continue;
    output_index[v] = static_cast<std::int32_t>(out.positions.size());
    out.positions.push_back(centroid[v]);
    if (has_normals) out.normals.push_back(normal[v]);
  }
  if (voxel_of_point) {
    for (std::size_t i = 0; i < n; ++i) (*voxel_of_point)[i] = output_index[voxel[i]];
  }
  return out;
}

std::vector<std::size_t> OnePerCellIndices(const std::vector<Eigen::Vector3d>& points,
                                           double cell_mm, CellPoint keep) {
  if (!(cell_mm > 0.0) || !std::isfinite(cell_mm))
    throw OptionError("OnePerCellIndices: cell_mm " + std::to_string(cell_mm) + " must be > 0");
  // Cell coordinates packed in 21 bits each (+-2^20 cells about the origin: +-1 km at 1 mm)
  // into one 64-bit key, kept in an open-addressing table of twice the points: one pass, no
  // allocation per point. Coordinates beyond that range fall back to a map of triples.
  constexpr std::int64_t kHalf = std::int64_t{1} << 20;
  const double inv = 1.0 / cell_mm;
  const auto cell_of = [&](const Eigen::Vector3d& p) {
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor(p.x() * inv)),
                                       static_cast<std::int64_t>(std::floor(p.y() * inv)),
                                       static_cast<std::int64_t>(std::floor(p.z() * inv))};
  };
  const auto centre_distance_sq = [&](const Eigen::Vector3d& p,
                                      const std::array<std::int64_t, 3>& c) {
    return (Eigen::Vector3d(c[0] + 0.5, c[1] + 0.5, c[2] + 0.5) * cell_mm - p).squaredNorm();
  };
  std::vector<std::size_t> out;
  std::vector<double> best;  // kNearestCentre: the kept point's distance to its cell's centre
  // Keeps point i for the cell whose output slot is k (k == out.size(): a new cell).
  const auto offer = [&](std::size_t k, std::size_t i, const std::array<std::int64_t, 3>& c) {
    const double d = keep == CellPoint::kNearestCentre ? centre_distance_sq(points[i], c) : 0.0;
    if (k == out.size()) {
      out.push_back(i);
      best.push_back(d);
    } else if (d < best[k]) {
      out[k] = i;
      best[k] = d;
    }
  };
  // The packed keys fit when the bounding box's cells do (cell_of is monotonic per axis).
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw InputError("OnePerCellIndices: point " + std::to_string(i) +
                       " is not finite; drop invalid points first");
    }
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  bool packable = true;
  if (!points.empty()) {
    for (std::int64_t c : cell_of(lo)) packable = packable && c >= -kHalf;
    for (std::int64_t c : cell_of(hi)) packable = packable && c < kHalf;
  }
  if (packable) {
    std::size_t size = 16;
    while (size < 2 * points.size()) size *= 2;
    std::vector<std::uint64_t> table(size, 0);  // 0 marks an empty slot
    std::vector<std::uint32_t> output_of(size, 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::array<std::int64_t, 3> c = cell_of(points[i]);
      std::uint64_t key = 1;
      for (std::int64_t v : c) key = (key << 21) | static_cast<std::uint64_t>(v + kHalf);
      std::size_t slot = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> 20) & (size - 1);
      while (table[slot] != 0 && table[slot] != key) slot = (slot + 1) & (size - 1);
      if (table[slot] == 0) {
        table[slot] = key;
        output_of[slot] = static_cast<std::uint32_t>(out.size());
      }
      offer(output_of[slot], i, c);
    }
  } else {
    struct KeyHash {
      std::size_t operator()(const std::array<std::int64_t, 3>& k) const {
        return static_cast<std::size_t>((static_cast<std::uint64_t>(k[0]) * 73856093ULL) ^
                                        (static_cast<std::uint64_t>(k[1]) * 19349663ULL) ^
                                        (static_cast<std::uint64_t>(k[2]) * 83492791ULL));
      }
    };
    std::unordered_map<std::array<std::int64_t, 3>, std::size_t, KeyHash> output_of;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const std::array<std::int64_t, 3> c = cell_of(points[i]);
      offer(output_of.emplace(c, out.size()).first->second, i, c);
    }
  }
  if (keep == CellPoint::kNearestCentre) std::sort(out.begin(), out.end());
  return out;
}

}  // namespace lasercell::registration
