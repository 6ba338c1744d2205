#pragma once
// Point-cloud and mesh files: PLY (ASCII, binary little/big endian; any property order;
// char/uchar/short/ushort/int/uint/float/double and their int8..float64 aliases; faces as
// list properties) and PCD (ascii, binary, binary_compressed; organized or not).
// Units: lasercell works in millimetres; files are read as they are (see ReadReport::unit_hint).
// Normals are returned unit length (normalized on read when a file stores them otherwise).
// Points with a non-finite coordinate or an invalid normal (NaN/inf or zero length) are never
// passed on: they are dropped and counted in ReadReport::dropped_non_finite (organized PCD keeps
// the grid cell of every kept point in profile/column). PLY faces are remapped to the kept
// vertices; a triangle that uses a dropped vertex is dropped too (ReadReport::dropped_faces).
// Writes are atomic (file_util.hpp) and default to binary PLY.
//
// Field names written and recognised: x y z, nx ny nz (PCD: normal_x normal_y normal_z),
// intensity, profile, column, timestamp (seconds). lasercell PLY files carry the comments
// "lasercell_format 1" and, for organized clouds, "lasercell_grid ROWS COLS"; PCD files carry
// the same as '#' comment lines. PCD is always written unorganized (WIDTH = points, HEIGHT = 1,
// no NaN filler) with profile/column as int fields, so nothing is lost.
// Reading also accepts normal_x.. in PLY, nx.. in PCD and "scalar_intensity" (CloudCompare).
// A PCD VIEWPOINT is validated but not applied (PCL semantics: acquisition metadata); a
// non-identity one is mentioned in ReadReport::notes.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/point_cloud.hpp"

namespace lasercell::io {

/// What a reader found in a file, beyond the cloud itself.
struct ReadReport {
  std::string format;              ///< e.g. "ply binary_little_endian", "pcd binary_compressed".
  std::size_t points_in_file = 0;  ///< Vertex/point count declared by the header.
  std::size_t dropped_non_finite =
      0;                  ///< Points dropped: NaN/inf position, NaN/inf or zero-length normal.
  std::size_t faces = 0;  ///< Triangles read (PLY meshes; polygons fanned).
  std::size_t dropped_faces = 0;            ///< Triangles dropped: they used a dropped vertex.
  std::vector<std::string> fields_in_file;  ///< Vertex property names in file order.
  std::vector<std::string> ignored_fields;  ///< Properties read but not kept (e.g. rgb, curvature).
  int lasercell_format_version = 0;         ///< From the file's comment; 0 for foreign files.
  std::string unit_hint;                    ///< Non-empty when the extent suggests metres, etc.
  /// Things worth knowing that are not errors: PLY elements skipped ("skipped element 'edge'
  /// (12 instances)"), a non-identity PCD VIEWPOINT that was not applied.
  std::vector<std::string> notes;
};

/// Non-empty when the cloud's bounding-box diagonal (under 10) looks like metres rather than
/// millimetres: the text of ReadReport::unit_hint, e.g. "extent 0.42 — looks like metres; ...".
std::string UnitHint(const PointCloud& cloud);
/// The same test on a bounding box already known (of `points` points).
std::string UnitHint(const BoundingBox& bounds, std::size_t points);

/// PLY encodings lasercell writes.
enum class PlyEncoding { kBinaryLittleEndian, kBinaryBigEndian, kAscii };

/// Options for writing clouds and meshes.
struct WriteOptions {
  PlyEncoding ply_encoding = PlyEncoding::kBinaryLittleEndian;  ///< PLY flavour.
  bool pcd_binary = true;            ///< PCD "DATA binary" (true) or "DATA ascii" (false).
  bool positions_as_double = false;  ///< PLY/PCD positions as float64 instead of float32.
};

/// Reads a .ply or .pcd (by extension, case-insensitive). Throws FileError naming the file and
/// the problem for anything it cannot read: missing file, bad magic or header, unknown
/// property types, truncated data, a declared count larger than the data could hold.
PointCloud ReadPointCloud(const std::string& path, ReadReport* report = nullptr);

/// Writes .ply or .pcd (by extension). Validates the cloud first; atomic.
void WritePointCloud(const std::string& path, const PointCloud& cloud,
                     const WriteOptions& options = {});

/// Reads a PLY mesh (vertices with attributes and triangular faces; polygons are fanned).
TriangleMesh ReadPlyMesh(const std::string& path, ReadReport* report = nullptr);
/// Writes a PLY mesh; atomic.
void WritePlyMesh(const std::string& path, const TriangleMesh& mesh,
                  const WriteOptions& options = {});

/// Parses PLY bytes already in memory; `name` is used in error messages.
TriangleMesh ParsePly(std::string_view bytes, const std::string& name,
                      ReadReport* report = nullptr);
/// Parses PCD bytes already in memory; `name` is used in error messages.
PointCloud ParsePcd(std::string_view bytes, const std::string& name, ReadReport* report = nullptr);
/// Encodes a cloud/mesh as PLY bytes (used by the writers; faces may be empty).
std::string EncodePly(const TriangleMesh& mesh, const WriteOptions& options = {});
/// Encodes a cloud as PCD bytes.
std::string EncodePcd(const PointCloud& cloud, const WriteOptions& options = {});

}  // namespace lasercell::io
