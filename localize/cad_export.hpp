#pragma once
// Writes small parametric solids (boxes and cylinders combined by union and difference) as STEP
// or IGES files, through OpenCASCADE: test parts with known analytic geometry and the
// simulator's CAD models. No OpenCASCADE type appears here.
//
// Conventions: sizes and placements in millimetres, in the part frame; `part_from_primitive`
// places each primitive's own frame (below) in the part. The file stores the solid in the
// requested length unit ("mm", "inch" or "m"), with the coordinates converted to it.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace lasercell::localize {

/// One primitive of a CadSolid, in its own frame:
///  - kBox: the axis-aligned box [0, size_mm.x] x [0, size_mm.y] x [0, size_mm.z] (a corner at
///    the origin);
///  - kCylinder: radius size_mm.x around the +z axis, from z = 0 to z = size_mm.y (size_mm.z
///    unused).
struct CadPrimitive {
  /// The primitive's shape.
  enum Kind { kBox, kCylinder };
  Kind kind = kBox;  ///< Box or cylinder.
  /// Pose of the primitive's frame in the part frame (mm); must be rigid.
  Eigen::Isometry3d part_from_primitive = Eigen::Isometry3d::Identity();
  /// Box: edge lengths x, y, z; cylinder: radius, height, unused. mm, > 0.
  Eigen::Vector3d size_mm = Eigen::Vector3d::Ones();
  /// When true the primitive is removed from the solid built so far, else added to it.
  bool subtract = false;
};

/// A solid built from primitives in order: the first must be additive; each further one is
/// united with (or, when `subtract`, cut from) the result so far.
struct CadSolid {
  std::vector<CadPrimitive> primitives;  ///< In the order they are applied.
};

/// Builds `solid` and writes it to `path` as STEP (.step, .stp: AP214) or IGES (.iges, .igs:
/// B-rep solid entities), chosen by the extension (case-insensitive), in length unit `unit`
/// ("mm", "inch" or "m"). The write is atomic (a temporary file beside `path`, then renamed).
/// STEP bytes depend only on the solid, the unit and the file name (the product is named after
/// the file's stem, the header time stamp is fixed at 1970-01-01T00:00:00).
/// Throws InputError for an empty solid, a first primitive that subtracts, a size that is not
/// positive and finite, a placement that is not rigid, an unknown extension or unit, or a
/// boolean operation that fails or leaves nothing; FileError when the file cannot be written.
void WriteCadSolid(const std::string& path, const CadSolid& solid, const std::string& unit = "mm");

}  // namespace lasercell::localize
