#pragma once
// Ray casting in the simulated cell. Objects are triangle meshes with analytic patches
// (geometry.hpp) and a diffuse material; Embree 3 finds the first triangle a ray meets (single
// precision, watertight "robust" mode), then the hit is recomputed in double precision against
// the analytic surface the triangle belongs to (plane, sphere, cylinder) or, for free-form
// surfaces, against the triangle's own plane with the double-precision vertices. Points on planes
// and spheres are therefore exact to ~1e-10 mm; the mesh only decides *which* surface a ray
// meets (curved surfaces are inscribed tessellations, so silhouettes are off by at most the
// chord sagitta, e.g. 0.008 mm for a 25 mm sphere with 128 segments).
//
// Frame: everything is expressed in one scene frame (the simulator uses `cell`). Units mm.
// Thread safety: after Commit(), Intersect/Occluded may be called from many threads.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "datasets/geometry.hpp"

namespace lasercell::datasets {

/// Diffuse reflectance at the laser wavelength, optionally a chessboard pattern.
struct Material {
  double albedo = 0.5;  ///< Lambertian reflectance in [0, 1] (outside the pattern).
  /// Chessboard pattern (squares_x * squares_y squares of square_mm) in the xy plane of
  /// `pattern_from_scene`'s frame, starting at its origin; square (i, j) is dark when i + j is
  /// even. Off when squares_x == 0.
  int squares_x = 0;
  int squares_y = 0;
  double square_mm = 0.0;
  double dark_albedo = 0.05;  ///< Albedo of dark squares.
  Eigen::Isometry3d pattern_from_scene = Eigen::Isometry3d::Identity();

  /// Albedo at a point on the object (scene frame).
  double AlbedoAt(const Eigen::Vector3d& p_in_scene) const;
};

/// One object of the scene.
struct SceneObject {
  std::string name;   ///< e.g. "pallet", "seat", "sphere_2".
  MeshPart geometry;  ///< In the scene frame.
  Material material;
};

/// A ray's first hit.
struct RayHit {
  double t_mm = 0.0;                                  ///< Distance along the unit direction.
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    ///< Hit point, scene frame, mm.
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< Outward unit surface normal.
  std::int32_t object = -1;                           ///< Index of the object hit.
  std::int32_t face = -1;                             ///< Face of that object's mesh.
};

/// A set of objects with an Embree BVH.
class Scene {
 public:
  Scene();
  ~Scene();
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  /// Adds an object (before Commit) and returns its index.
  std::int32_t Add(SceneObject object);
  /// Builds the acceleration structure. Throws InternalError when Embree fails.
  void Commit();

  /// First hit along origin + t * direction for t in (t_min, t_max); direction need not be unit
  /// (it is normalized; t is in mm). Requires Commit().
  std::optional<RayHit> Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double t_min = 0.0,
                                  double t_max = std::numeric_limits<double>::infinity()) const;
  /// True when anything lies on the segment t in (t_min, t_max).
  bool Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                double t_max) const;
  /// Intersects the ray (unit direction) with the surface of one face only, in double precision:
  /// the face's analytic patch (root nearest `t_hint`), or the plane of a free-form triangle.
  /// Returns nullopt when the ray misses that surface or the triangle by more than `slack_mm`.
  std::optional<RayHit> IntersectFace(std::int32_t object, std::int32_t face,
                                      const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& unit_direction, double t_hint,
                                      double slack_mm = 1e-3) const;

  /// Albedo of object `object` at a point on it.
  double AlbedoAt(std::int32_t object, const Eigen::Vector3d& p) const {
    return objects_[object].material.AlbedoAt(p);
  }
  const std::vector<SceneObject>& objects() const { return objects_; }
  /// Index of the object with this name, or -1.
  std::int32_t Find(const std::string& name) const;
  /// All objects' meshes merged into one (e.g. for PLY export).
  TriangleMesh MergedMesh() const;
  /// Number of triangles.
  std::size_t TriangleCount() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<SceneObject> objects_;
  std::vector<std::vector<Eigen::Vector3d>> face_normals_;  // per object, per face (double)
};

}  // namespace lasercell::datasets
