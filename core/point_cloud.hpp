#pragma once
// Conventions for the whole toolkit (ARCHITECTURE.md):
//  - Units: millimetres and radians; time in seconds (double) unless a name says otherwise.
//  - Points are expressed in one frame, named by the owner (`p_in_sensor`, `cloud_in_base`).
//  - Transforms are `target_from_source` (Eigen::Isometry3d): p_in_base = base_from_sensor * p.
//  - A PointCloud is a structure of arrays: `positions` always, every other attribute either
//    empty (absent) or exactly positions.size() long. Validate() enforces this.
//  - Organized clouds (sweeps, depth images) keep their grid: grid_rows x grid_cols, and each
//    point's `profile` (row) and `column`. Invalid grid cells are simply absent, so positions
//    are always finite.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace lasercell {

/// Axis-aligned bounding box, mm. Empty when min > max (the default).
struct BoundingBox {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

  /// True when no point was added.
  bool Empty() const { return (min.array() > max.array()).any(); }
  /// Grows the box to contain p.
  void Extend(const Eigen::Vector3d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  /// Edge lengths, mm (zero vector when empty).
  Eigen::Vector3d Size() const {
    return Empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(max - min);
  }
  /// Length of the diagonal, mm.
  double Diagonal() const { return Size().norm(); }
  /// Centre of the box, mm.
  Eigen::Vector3d Center() const { return 0.5 * (min + max); }
  /// True when p lies inside or on the boundary.
  bool Contains(const Eigen::Vector3d& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
};

/// A point cloud with optional per-point attributes (structure of arrays).
struct PointCloud {
  std::vector<Eigen::Vector3d> positions;  ///< Point positions, mm. Always finite.
  std::vector<Eigen::Vector3d> normals;    ///< Unit normals, or empty.
  std::vector<float> intensity;            ///< Sensor intensity (arbitrary units), or empty.
  std::vector<std::int32_t> profile;       ///< Sweep profile index / image row, or empty.
  std::vector<std::int32_t> column;        ///< Sensor column / image column, or empty.
  std::vector<double> timestamp_s;         ///< Acquisition time, seconds, or empty.
  std::int32_t grid_rows = 0;  ///< Rows (profiles) of the organized grid; 0 when unorganized.
  std::int32_t grid_cols = 0;  ///< Columns of the organized grid; 0 when unorganized.

  /// Number of points.
  std::size_t size() const { return positions.size(); }
  /// True when the cloud has no points.
  bool empty() const { return positions.empty(); }
  bool HasNormals() const { return !normals.empty(); }
  bool HasIntensity() const { return !intensity.empty(); }
  bool HasProfile() const { return !profile.empty(); }
  bool HasColumn() const { return !column.empty(); }
  bool HasTimestamps() const { return !timestamp_s.empty(); }
  /// True when the cloud has a grid and every point knows its grid cell.
  bool IsOrganized() const { return grid_rows > 0 && grid_cols > 0 && HasProfile() && HasColumn(); }

  /// Throws InputError naming `what` when attribute sizes disagree with positions, a position
  /// is not finite, a normal is not finite, or grid indices fall outside the grid.
  void Validate(const std::string& what = "point cloud") const;
  /// Validate() without the pass over the positions, for a caller that checked each position
  /// for finiteness as it filled them (the Python bindings' array copy).
  void ValidateAttributes(const std::string& what) const;

  /// Bounding box of the positions.
  BoundingBox Bounds() const;
  /// Mean of the positions (zero for an empty cloud).
  Eigen::Vector3d Centroid() const;

  /// Applies `target_from_source` in place to positions and normals (rotation only).
  void Transform(const Eigen::Isometry3d& target_from_source);
  /// Returns a transformed copy.
  PointCloud Transformed(const Eigen::Isometry3d& target_from_source) const;
  /// Returns the points at `indices` with all their attributes (grid kept).
  PointCloud Subset(std::span<const std::size_t> indices) const;
  /// Appends another cloud; both must carry the same attributes.
  void Append(const PointCloud& other);
  /// Reserves room for n points in every present attribute.
  void Reserve(std::size_t n);
  /// Names of the attributes present, e.g. "x y z nx ny nz intensity".
  std::string FieldNames() const;
};

/// A triangle mesh: vertices (with optional attributes) and index triples.
struct TriangleMesh {
  PointCloud vertices;  ///< Vertex positions (and normals when known), mm.
  std::vector<Eigen::Vector3i>
      faces;  ///< Vertex index triples, counter-clockwise seen from outside.
};

}  // namespace lasercell
