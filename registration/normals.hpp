#pragma once
// Surface normals by local plane fit (PCA) on k nearest neighbours or a radius (Skotheim et al.
// 2012, IV-B), oriented toward the sensor. Units: mm; normals are unit.
// Organized clouds (sweeps, depth images) can use their grid neighbours instead of a kd-tree.
// Multi-threaded with TBB; the result does not depend on the thread count.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/point_cloud.hpp"
#include "registration/viewpoint.hpp"

namespace lasercell::registration {

/// Options for EstimateNormals.
struct NormalOptions {
  /// Neighbours per plane fit (kd-tree path), including the point itself (>= 3).
  std::size_t k = 12;
  /// When > 0, use every neighbour within this radius (mm) instead of the k nearest.
  double radius_mm = 0.0;
  /// Orientation: normals point toward the sensor (unless per-point line of sight is given).
  Viewpoint viewpoint;
  /// Organized clouds: use grid neighbours (+-grid_window rows/columns) when true.
  bool use_grid_when_organized = true;
  /// Half-width of the grid neighbourhood, cells (2 = 5x5 window).
  int grid_window = 2;
  /// Grid neighbours farther than this from the point are ignored (depth jumps), mm; 0 = no limit.
  double grid_max_distance_mm = 0.0;
  /// Fewer neighbours than this (including the point) leave the point without a normal (>= 3).
  std::size_t min_neighbors = 3;
  /// Worker threads: 0 = all cores, 1 = calling thread only.
  int threads = 0;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// Normals and, per point, whether the fit succeeded.
struct NormalEstimationResult {
  std::vector<Eigen::Vector3d> normals;  ///< Unit normal per point (zero when invalid).
  std::vector<std::uint8_t> valid;       ///< 1 when the plane fit had enough neighbours.
  std::vector<float> curvature;   ///< Surface variation l0/(l0+l1+l2) per point, in [0, 1/3].
  std::size_t invalid_count = 0;  ///< Points without a normal.
  bool used_grid = false;         ///< True when grid neighbours were used.
};

/// PCA plane fit per point: normal = eigenvector of the smallest eigenvalue of the neighbourhood
/// covariance, flipped to face the sensor. `line_of_sight`, when not empty, gives per point a
/// vector from the point toward the sensor (sweeps with a moving sensor) and overrides the
/// viewpoint. Throws InputError when the cloud is invalid or line_of_sight has the wrong size.
NormalEstimationResult EstimateNormals(const PointCloud& cloud, const NormalOptions& options,
                                       std::span<const Eigen::Vector3d> line_of_sight = {});

/// The same fit for the points `at` of `cloud` only, each from its neighbourhood in the whole
/// cloud (grid or kd-tree, as EstimateNormals): slot k of the result is point at[k]. For work
/// that needs normals at a thinned subset of a dense scan, at the dense scan's neighbourhoods.
/// `line_of_sight`, when not empty, has one vector per point of `cloud`. Throws InputError also
/// for an index out of range.
NormalEstimationResult EstimateNormalsAt(const PointCloud& cloud, std::span<const std::size_t> at,
                                         const NormalOptions& options,
                                         std::span<const Eigen::Vector3d> line_of_sight = {});

/// A cloud with normals fitted where later work reads them (WithNormalsAtCells).
struct CloudWithNormals {
  PointCloud cloud;               ///< The kept points with their unit normals.
  std::vector<std::size_t> kept;  ///< Index in the input cloud of each kept point.
  std::size_t dropped = 0;        ///< Points whose fit failed (not kept).
};

/// Normals where they are read: with `cell_mm` > 0 the cloud is first thinned to one point per
/// cell of that size, the one nearest the cell's centre (OnePerCellIndices with
/// CellPoint::kNearestCentre, so the means taken later are not pulled to the side a scan entered
/// each cell from), and normals are fitted at those points only, each from its neighbourhood in
/// the whole cloud (EstimateNormalsAt); with 0, at every point (EstimateNormals). Points without
/// a valid fit are dropped. `line_of_sight` as for EstimateNormals. Throws as those do.
CloudWithNormals WithNormalsAtCells(const PointCloud& cloud, double cell_mm,
                                    const NormalOptions& options,
                                    std::span<const Eigen::Vector3d> line_of_sight = {});

/// A copy of `cloud` with normals from EstimateNormals; points without a valid fit are dropped
/// (their count in *dropped when given).
PointCloud WithEstimatedNormals(const PointCloud& cloud, const NormalOptions& options,
                                std::size_t* dropped = nullptr);

/// Vertex normals of a triangle mesh (a CAD model): the area-weighted sum of the normals of
/// the faces that use the vertex, unit length, oriented by the faces' winding (counter-clockwise
/// seen from outside gives outward normals). Unlike a PCA fit this keeps the two sides of a thin
/// shell apart and needs no viewpoint. A vertex no face uses, or whose faces cancel, gets a
/// zero normal. Throws InputError when the mesh has no faces or a face index is out of range.
std::vector<Eigen::Vector3d> MeshVertexNormals(const TriangleMesh& mesh);

/// The mesh's vertices with MeshVertexNormals; vertices without a normal are dropped (their
/// count in *dropped when given).
PointCloud WithMeshNormals(const TriangleMesh& mesh, std::size_t* dropped = nullptr);

/// Flips every normal to face the sensor (n . (sensor - p) >= 0). Normals must be present.
void OrientNormalsTowardViewpoint(PointCloud* cloud, const Viewpoint& viewpoint);

}  // namespace lasercell::registration
