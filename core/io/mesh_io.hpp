#pragma once
// Triangle-mesh files as CAD users export them: STL (binary and ASCII), Wavefront OBJ, and PLY
// (point_cloud_io.hpp). ReadMesh picks the reader by extension.
//
// Binary STL (little-endian): 80-byte header, u32 triangle count, then per triangle 12 float32
// (unit normal, three vertices, counter-clockwise seen from outside) and a u16 attribute (0).
// ASCII STL: "solid NAME", then per facet "facet normal nx ny nz / outer loop / vertex x y z (x3)
// / endloop / endfacet", then "endsolid". A file is binary when its size is exactly 84 + 50 x the
// declared count (some exporters start binary headers with "solid"), ASCII when it starts with
// "solid" otherwise. The stored facet normals are not used: faces keep their vertex order.
// OBJ: `v x y z [w]` and `f i j k ...` (1-based or negative indices, with /vt/vn parts; polygons
// fanned); texture, normal, group, material and smoothing statements are skipped.
// STL and OBJ carry no units: coordinates are returned as written (the caller applies the
// part's declared unit). Vertices with identical coordinates are merged (first-seen order), so a
// closed STL mesh reads back with shared vertices. Writes are atomic (file_util.hpp); binary STL
// rounds coordinates to float32 (~1e-5 mm at 200 mm).

#include <string>
#include <string_view>

#include "core/io/point_cloud_io.hpp"
#include "core/point_cloud.hpp"

namespace lasercell::io {

/// Encodes a mesh as binary STL; `header` (at most 80 bytes, padded with zeros) must not start
/// with "solid" (readers would take the file for ASCII STL). Face normals are computed from the
/// double-precision vertices. Throws InputError for a face index out of range, a header too
/// long or starting with "solid".
std::string EncodeBinaryStl(const TriangleMesh& mesh, const std::string& header = "lasercell");
/// Encodes a mesh as ASCII STL (solid `name`), coordinates printed to round-trip exactly.
std::string EncodeAsciiStl(const TriangleMesh& mesh, const std::string& name = "lasercell");

/// Parses STL bytes, binary or ASCII (see the file comment); `name` appears in errors. Throws
/// FileError naming `name` when the size does not match the triangle count, an ASCII line is not
/// what the grammar expects (with its line number) or a coordinate is not finite.
TriangleMesh DecodeStl(std::string_view bytes, const std::string& name);
/// Parses OBJ text; `name` appears in errors. Throws FileError with the line number for a
/// malformed vertex or face, an index out of range or a non-finite coordinate.
TriangleMesh DecodeObj(std::string_view text, const std::string& name);

/// Writes binary STL atomically. Throws FileError.
void WriteStlMesh(const std::string& path, const TriangleMesh& mesh);
/// Reads STL (binary or ASCII). Throws FileError.
TriangleMesh ReadStlMesh(const std::string& path);

/// Reads a mesh by extension (case-insensitive): .stl, .obj, .ply. `report` (optional) gets the
/// format and face count (PLY: everything ReadPlyMesh reports). Throws FileError naming the file
/// for an unknown extension or unreadable content.
TriangleMesh ReadMesh(const std::string& path, ReadReport* report = nullptr);
/// Writes a mesh by extension (case-insensitive), atomically: .stl (binary) or .ply. Throws
/// FileError naming the file for another extension or when it cannot be written, InputError for
/// a face index out of range.
void WriteMesh(const std::string& path, const TriangleMesh& mesh);

}  // namespace lasercell::io
