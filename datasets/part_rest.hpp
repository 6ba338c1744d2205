#pragma once
// How a rigid part lies on a horizontal plane, and the footprint tests of a pallet scene.
//
// A part at rest on a plane touches it with vertices of its convex hull, and the vertical
// through its centre of mass meets the support polygon (the convex hull of the contacts) inside
// (a stable pose of the quasi-static rigid body). SettleOnPlane finds one by letting the part
// fall from a start orientation: it pivots about the contact point or edge nearest the centre
// of mass's projection until a further vertex touches, and repeats until that projection lies
// inside the support polygon. The centre of mass is that of a homogeneous solid bounded by a
// closed, outward mesh (divergence theorem over the triangles).
//
// Frames: `plane` has the resting plane at z = 0, +z up; `part` is the mesh's frame. Units mm.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "core/point_cloud.hpp"

namespace lasercell::datasets {

/// Closedness, orientation and mass properties of a triangle mesh meant to bound a solid.
struct MeshSolidCheck {
  std::size_t boundary_edges = 0;  ///< Edges used by one triangle only (cracks, open borders).
  /// Edges used by more than two triangles, or twice in the same direction (two neighbours of
  /// opposite orientation): the mesh does not bound one consistently oriented solid there.
  std::size_t inconsistent_edges = 0;
  double volume_mm3 = 0;  ///< Signed enclosed volume: positive when the faces point outward.
  Eigen::Vector3d center_of_mass = Eigen::Vector3d::Zero();  ///< Of the homogeneous solid, mm.
  /// True when every edge joins exactly two triangles in opposite directions and the volume is
  /// positive: a closed, outward mesh.
  bool ClosedAndOutward() const {
    return boundary_edges == 0 && inconsistent_edges == 0 && volume_mm3 > 0;
  }
};

/// Checks a mesh. Vertices at bit-identical positions are one vertex (meshes whose faces each
/// hold their own copies of the shared edge points, such as localize::ReadCadModel's, are
/// welded so).
MeshSolidCheck CheckMeshSolid(const TriangleMesh& mesh);

/// A stable resting pose found by SettleOnPlane.
struct RestingPose {
  /// The part on the plane: its lowest vertices at z = 0.
  Eigen::Isometry3d plane_from_part = Eigen::Isometry3d::Identity();
  /// The support: vertices within the contact tolerance of the plane that span the support
  /// polygon (its corners, counter-clockwise seen from above).
  std::vector<Eigen::Vector3d> contacts_in_part;
  /// Distance from the centre of mass's projection to the nearest edge of the support polygon
  /// (positive inside), mm.
  double stability_margin_mm = 0;
  int pivots = 0;  ///< Pivot steps taken from the start orientation.
};

/// Lets the part (mesh vertices and centre of mass in the part frame) settle on the plane z = 0
/// from the orientation plane_from_part = `start`. It pivots about the vertices that touch
/// exactly (to 1e-6 mm) and comes to rest once the centre of mass projects inside the support
/// polygon of the vertices within `contact_tolerance_mm` of the plane (> 0: a deck board and a
/// moulded part are not flat to better than a tenth of a millimetre, and a tessellated convex
/// rim would otherwise rock on single vertices). Throws InputError for fewer than three
/// vertices or a tolerance that is not positive, InternalError when the part does not come to
/// rest within 100 pivots.
RestingPose SettleOnPlane(const std::vector<Eigen::Vector3d>& vertices_in_part,
                          const Eigen::Vector3d& center_of_mass_in_part,
                          const Eigen::Matrix3d& start, double contact_tolerance_mm = 0.1);

/// Convex hull of 2D points, counter-clockwise, without collinear points (Andrew's monotone
/// chain). Fewer than three distinct points give those points.
std::vector<Eigen::Vector2d> ConvexHull2d(std::vector<Eigen::Vector2d> points);

/// Signed distance from `p` to the boundary of the counter-clockwise convex polygon `hull`
/// (positive inside), mm; for fewer than three vertices, minus the distance to them.
double SignedDistanceInside(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p);

/// True when two convex counter-clockwise polygons come closer than `gap_mm` (separating-axis
/// test on the edge normals; a gap of 0 tests for overlap).
bool ConvexPolygonsCloserThan(const std::vector<Eigen::Vector2d>& a,
                              const std::vector<Eigen::Vector2d>& b, double gap_mm);

}  // namespace lasercell::datasets
