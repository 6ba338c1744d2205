// File-level entry points: read the bytes, dispatch on the extension, add the unit hint;
// validate, encode and write atomically.
#include "core/io/point_cloud_io.hpp"

#include <cstdio>

#include "core/error.hpp"
#include "core/io/codec.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::io {
namespace {

enum class Format { kPly, kPcd };

Format FormatOf(const std::string& path, bool allow_pcd) {
  const std::string ext = LowerExtension(path);
  if (ext == ".ply") return Format::kPly;
  if (ext == ".pcd" && allow_pcd) return Format::kPcd;
  throw FileError(path, "unsupported extension '" + ext + "'; use " +
                            (allow_pcd ? ".ply or .pcd" : ".ply (meshes are PLY only)"));
}

}  // namespace

std::string UnitHint(const PointCloud& cloud) {
  if (cloud.size() < 2) return {};
  return UnitHint(cloud.Bounds(), cloud.size());
}

std::string UnitHint(const BoundingBox& bounds, std::size_t points) {
  if (points < 2) return {};
  const double diagonal = bounds.Diagonal();
  if (!(diagonal > 0.0 && diagonal < 10.0)) return {};
  char buf[160];
  std::snprintf(buf, sizeof(buf),
                "extent %.3g \xE2\x80\x94 looks like metres; lasercell expects millimetres "
                "(scale by 1000)",
                diagonal);
  return buf;
}

PointCloud ReadPointCloud(const std::string& path, ReadReport* report) {
  const Format format = FormatOf(path, true);
  const MappedFile file(path);
  ReadReport local;
  PointCloud cloud = format == Format::kPly
                         ? std::move(ParsePly(file.bytes(), path, &local).vertices)
                         : ParsePcd(file.bytes(), path, &local);
  local.unit_hint = UnitHint(cloud);
  if (report != nullptr) *report = std::move(local);
  return cloud;
}

TriangleMesh ReadPlyMesh(const std::string& path, ReadReport* report) {
  FormatOf(path, false);
  const MappedFile file(path);
  ReadReport local;
  TriangleMesh mesh = ParsePly(file.bytes(), path, &local);
  local.unit_hint = UnitHint(mesh.vertices);
  if (report != nullptr) *report = std::move(local);
  return mesh;
}

void WritePointCloud(const std::string& path, const PointCloud& cloud,
                     const WriteOptions& options) {
  const Format format = FormatOf(path, true);
  detail::CheckWritable(cloud, {}, options, "cloud to write to " + path);
  WriteFileAtomically(path, format == Format::kPly ? detail::EncodePlyUnchecked(cloud, {}, options)
                                                   : detail::EncodePcdUnchecked(cloud, options));
}

void WritePlyMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options) {
  FormatOf(path, false);
  detail::CheckWritable(mesh.vertices, mesh.faces, options, "mesh to write to " + path);
  WriteFileAtomically(path, detail::EncodePlyUnchecked(mesh.vertices, mesh.faces, options));
}

}  // namespace lasercell::io
