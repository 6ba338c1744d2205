#pragma once
// Scene geometry of the simulated cell as triangle meshes that remember the analytic surface
// each triangle approximates (plane, sphere, cylinder, or none for free-form surfaces). The ray
// caster (scene.hpp) uses the analytic surface to refine Embree's single-precision hits to
// double precision. Units mm, rad. Every builder takes `frame_from_primitive` and returns the
// mesh expressed in `frame`. Curved surfaces are tessellated with vertices on the analytic
// surface (inscribed), faces counter-clockwise seen from outside.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/point_cloud.hpp"

namespace lasercell::datasets {

/// The exact surface a group of triangles approximates.
struct AnalyticSurface {
  enum class Kind : std::uint8_t {
    kNone,      ///< Free-form: the triangles themselves are the truth.
    kPlane,     ///< Plane through `point` with unit normal `axis` (facets are exact).
    kSphere,    ///< Sphere of `radius` about `point`.
    kCylinder,  ///< Infinite cylinder of `radius` about the line (`point`, unit `axis`).
  };
  Kind kind = Kind::kNone;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< See Kind, mm.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< Unit normal or axis.
  double radius = 0.0;                              ///< Sphere/cylinder radius, mm.

  /// Signed distance of p from the surface (outside positive), mm; 0 for kNone.
  double SignedDistance(const Eigen::Vector3d& p) const;
  /// The surface expressed in another frame.
  AnalyticSurface Transformed(const Eigen::Isometry3d& to_from_this) const;
};

/// A triangle mesh whose faces each point to an analytic surface ("patch").
struct MeshPart {
  TriangleMesh mesh;                     ///< Vertices (positions only) and faces.
  std::vector<std::int32_t> face_patch;  ///< Patch index of every face.
  std::vector<AnalyticSurface> patches;  ///< Patches referenced by face_patch.

  /// Appends another part (indices shifted).
  void Append(const MeshPart& other);
  /// Applies `to_from_this` to vertices and patches in place.
  void Transform(const Eigen::Isometry3d& to_from_this);
  /// Adds a patch and returns its index.
  std::int32_t AddPatch(const AnalyticSurface& surface);
  /// Adds a vertex and returns its index.
  std::int32_t AddVertex(const Eigen::Vector3d& p);
  /// Adds a face of patch `patch`.
  void AddFace(std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t patch);
  /// Throws InternalError when indices or patch references are out of range.
  void CheckConsistent() const;
};

/// Box of full edge lengths `size_mm` centred on the primitive origin; 6 plane patches.
MeshPart MakeBox(const Eigen::Isometry3d& frame_from_box, const Eigen::Vector3d& size_mm);

/// Rectangle in the primitive's z = 0 plane, normal +z, centred on the origin.
MeshPart MakeRectangle(const Eigen::Isometry3d& frame_from_rect, double size_x_mm,
                       double size_y_mm);

/// Cylinder along the primitive's +z from z = 0 to z = height, with caps when asked.
MeshPart MakeCylinder(const Eigen::Isometry3d& frame_from_cylinder, double radius_mm,
                      double height_mm, int segments, bool bottom_cap, bool top_cap);

/// Half sphere (z >= 0) of `radius_mm` about the primitive origin, open at the equator.
MeshPart MakeHemisphere(const Eigen::Isometry3d& frame_from_sphere, double radius_mm, int segments,
                        int rings);

/// Full sphere about the primitive origin (used in tests).
MeshPart MakeSphere(const Eigen::Isometry3d& frame_from_sphere, double radius_mm, int segments,
                    int rings);

/// A EUR-like pallet (1200 x 800 x 144 mm): 5 top deck boards, 9 blocks, 3 bottom boards;
/// origin at the centre of the top face's footprint on the floor, +z up, top at z = 144.
MeshPart MakePallet();
/// Height of MakePallet's top deck above its base, mm.
inline constexpr double kPalletHeightMm = 144.0;
/// MakePallet's top deck boards, each as its [y_min, y_max] in the pallet frame, mm; they run
/// the pallet's full length (x in [-600, 600]), with gaps between them.
std::vector<Eigen::Vector2d> PalletDeckBoards();

}  // namespace lasercell::datasets
