#pragma once
// CAD part models from STEP (ISO 10303-21) and IGES 5.3 files, read through OpenCASCADE.
//
// Conventions (ARCHITECTURE.md): everything returned is in millimetres in the part's own frame
// (the CAD file's coordinate system, `part`), whatever length unit the file declares; the file's
// unit and the factor applied are reported. Normals are unit and point out of the material
// (outward), both for the mesh and for the sampled points. No OpenCASCADE type appears here: the
// boundary is plain Eigen/std and core/point_cloud.hpp, and every OpenCASCADE failure becomes a
// lasercell::InputError naming the file.
//
// Thread safety: OpenCASCADE's data-exchange settings (target unit, ...) are process-wide, so
// ReadCadModel and WriteCadSolid (cad_export.hpp) serialize their use of them behind one mutex.

#include <cstddef>
#include <string>

#include "core/point_cloud.hpp"

namespace lasercell::localize {

/// Options for ReadCadModel.
struct CadImportOptions {
  /// Spacing of the oriented points sampled on the faces, mm (> 0). Each face is sampled on a
  /// grid in its (u, v) parameters whose steps are this long on the surface.
  double sampling_step_mm = 1.0;
  /// Tessellation of the returned mesh: largest distance between a triangle and the surface
  /// (chord error), mm (> 0).
  double linear_deflection_mm = 0.05;
  /// Tessellation: largest angle between the normals at the ends of a triangle edge, rad (> 0).
  double angular_deflection_rad = 0.3;
  /// Longest a read may take, s (> 0): OpenCASCADE can loop on a damaged file; the read runs in
  /// a child process that is killed after this long. Not part of a model's identity.
  double timeout_s = 600.0;
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// A part model read from a CAD file, in millimetres.
struct CadModel {
  /// The tessellated boundary: per face its own vertices (shared along the face's edges with the
  /// neighbouring faces' positions), triangles counter-clockwise seen from outside, vertex
  /// normals evaluated on the exact surface (outward).
  TriangleMesh mesh;
  /// Oriented points sampled on the exact faces at about sampling_step_mm (inside the trimmed
  /// face, never outside its boundary), with the exact outward unit surface normal there.
  /// Deterministic: the same file and options give the same points.
  PointCloud samples;
  /// "step" or "iges".
  std::string format;
  /// The length unit the file declares: "mm", "cm", "m", "um", "inch", "ft", ... When the roots
  /// of a STEP file declare different units, they are listed separated by ", ".
  std::string source_unit;
  /// Millimetres per file unit, the factor applied to the file's coordinates (of the first root
  /// when the roots differ; OpenCASCADE converts each root with its own unit).
  double scale_to_mm = 1.0;
  // Topology of the part as read; a file of loose faces (IGES trimmed surfaces, the usual IGES
  // export) is first sewn into shells, and each closed shell made a solid, so its normals can be
  // oriented outward.
  std::size_t solids = 0;  ///< Solids in the part.
  std::size_t shells = 0;  ///< Shells (closed or open) in the part.
  std::size_t faces = 0;   ///< Faces in the part.
  /// Area of all faces on the exact surfaces (Gauss integration, not the mesh), mm^2.
  double surface_area_mm2 = 0;
};

/// Reads a STEP (.step, .stp) or IGES (.iges, .igs) file, chosen by the extension
/// (case-insensitive), converts it to millimetres, sews loose faces into solids (see `solids`),
/// tessellates it and samples oriented points on its faces. Throws FileError when the file is
/// missing or unreadable; InputError when the extension is neither STEP nor IGES, the content is
/// not a readable file of that format (with the reader's status), the file declares an unknown
/// length unit, it holds no faces (e.g. only curves or points), or OpenCASCADE fails on it;
/// OptionError for bad options. Every message names the file and says what to do.
CadModel ReadCadModel(const std::string& path, const CadImportOptions& options = {});

}  // namespace lasercell::localize
