#pragma once
// Binary STL export of the simulator's meshes (the localizer's CAD models), next to PLY.
//
// Binary STL (little-endian): 80-byte header, u32 triangle count, then per triangle 12 float32
// (unit normal, three vertices, counter-clockwise seen from outside) and a u16 attribute (0).
// Units mm, as in the meshes. Coordinates are rounded to float32 (~1e-5 mm at 200 mm).

#include <string>
#include <string_view>

#include "core/point_cloud.hpp"

namespace lasercell::datasets {

/// Encodes a mesh as binary STL; `header` (at most 80 bytes, padded with zeros) must not start
/// with "solid" (readers would take the file for ASCII STL). Face normals are computed from the
/// double-precision vertices. Throws InputError for a face index out of range, a header too
/// long or starting with "solid".
std::string EncodeBinaryStl(const TriangleMesh& mesh, const std::string& header = "lasercell");

/// Parses binary STL bytes; `name` appears in errors. Vertices with identical float32
/// coordinates are merged (first-seen order), so a closed mesh reads back with shared vertices.
/// Throws InputError when the size does not match the triangle count.
TriangleMesh DecodeBinaryStl(std::string_view bytes, const std::string& name);

/// Writes binary STL atomically (core/io WriteFileAtomically). Throws FileError.
void WriteStlMesh(const std::string& path, const TriangleMesh& mesh);
/// Reads binary STL. Throws FileError / InputError.
TriangleMesh ReadStlMesh(const std::string& path);

}  // namespace lasercell::datasets
