#pragma once
// Preprocessing filters (Skotheim et al. 2012, IV-A and IV-C):
// region-of-interest box crop, removal of small isolated connected components, and voxel-grid
// centroid subsampling. Units: mm. Filters return indices into the input (so every attribute
// can be carried with PointCloud::Subset) or a new cloud; they never modify their input.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/point_cloud.hpp"

namespace lasercell::registration {

/// Indices of the points inside `box_in_frame` (inclusive), where each point is first mapped by
/// `frame_from_cloud` (identity: the box is in the cloud's own frame). Ascending order.
std::vector<std::size_t> CropBoxIndices(
    const PointCloud& cloud, const BoundingBox& box_in_frame,
    const Eigen::Isometry3d& frame_from_cloud = Eigen::Isometry3d::Identity());

/// The points inside the box, with all their attributes (see CropBoxIndices).
PointCloud CropBox(const PointCloud& cloud, const BoundingBox& box_in_frame,
                   const Eigen::Isometry3d& frame_from_cloud = Eigen::Isometry3d::Identity());

/// Options for RemoveSmallClusters.
struct ClusterFilterOptions {
  /// Two points are connected when closer than this, mm. Pick ~2-3x the point spacing.
  double radius_mm = 2.0;
  /// Components with fewer points are removed.
  std::size_t min_cluster_size = 50;
  /// For organized clouds: use grid adjacency (neighbours within +-grid_window rows/columns that
  /// are also within radius_mm) instead of a kd-tree. Much faster on sweeps.
  bool use_grid_when_organized = true;
  /// Half-width of the grid neighbourhood in cells (1 = 8-neighbourhood).
  int grid_window = 1;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// What RemoveSmallClusters found.
struct ClusterFilterResult {
  std::vector<std::int32_t> labels;    ///< Component id per input point (ids by first point).
  std::vector<std::size_t> kept;       ///< Indices of points in large-enough components, ascending.
  std::size_t components = 0;          ///< Number of connected components.
  std::size_t removed_components = 0;  ///< Components smaller than min_cluster_size.
  bool used_grid = false;              ///< True when grid adjacency was used.
};

/// Connected components by radius (kd-tree) or by grid adjacency on organized clouds, and the
/// points of components with at least min_cluster_size points. Deterministic.
ClusterFilterResult RemoveSmallClusters(const PointCloud& cloud,
                                        const ClusterFilterOptions& options);

/// How a voxel's normal is formed.
enum class VoxelNormalMode {
  kAverage,       ///< Mean of the normals in the voxel, renormalized.
  kNearestPoint,  ///< Normal of the input point nearest to the voxel centroid ("carried").
  kNone,          ///< Output has no normals.
};

/// Options for VoxelGridDownsample.
struct VoxelGridOptions {
  double voxel_size_mm = 1.0;                               ///< Edge of the cubic voxels, mm (> 0).
  VoxelNormalMode normal_mode = VoxelNormalMode::kAverage;  ///< Ignored when input has no normals.
  /// With kAverage: drop voxels whose mean normal is shorter than this (normals disagree, e.g.
  /// on a sharp edge); 0 keeps every voxel. In [0, 1].
  double min_normal_coherence = 0.0;
  std::size_t min_points_per_voxel = 1;  ///< Voxels with fewer points are dropped (>= 1).
  /// 0: one sample per voxel. > 0 (rad, at most pi): a point whose normal is more than this
  /// angle from the first normal of each of its voxel's samples starts a sample of its own, so
  /// the two faces of a wall thinner than the voxel stay apart instead of averaging to a point
  /// inside the wall with a meaningless normal. Needs normals; ignored without them.
  double normal_split_angle_rad = 0.0;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// Voxel-grid centroid subsampling: one point per occupied voxel at the centroid of its points
/// (Skotheim IV-C), or one per normal group of a voxel with normal_split_angle_rad > 0. Output
/// order is the order in which voxels are first hit by the input, so it is deterministic.
/// `voxel_of_point`, when given, receives for every input point the index of its output point (or
/// -1 when its voxel was dropped). Output keeps positions and normals only.
PointCloud VoxelGridDownsample(const PointCloud& cloud, const VoxelGridOptions& options,
                               std::vector<std::int32_t>* voxel_of_point = nullptr);

/// Which point of a cell OnePerCellIndices keeps.
enum class CellPoint {
  kFirst,          ///< The first in input order.
  kNearestCentre,  ///< The nearest the cell's centre (ties: the first): no bias toward the side
                   ///< a scan enters the cells from, for points whose means are taken later.
};

/// Indices of one point per occupied cubic cell of edge `cell_mm` (> 0), ascending, deterministic.
/// Every input point has a kept point within sqrt(3) x cell_mm wherever the cells fall: a
/// spatial thinning that, unlike an index stride, leaves no gaps along the rows of an organized
/// scan. Throws OptionError for a bad cell, InputError for a non-finite point.
std::vector<std::size_t> OnePerCellIndices(const std::vector<Eigen::Vector3d>& points,
                                           double cell_mm, CellPoint keep = CellPoint::kFirst);

}  // namespace lasercell::registration
