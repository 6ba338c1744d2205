// PLY writer, and the vertex bodies PLY and PCD share. Vertex fields in a fixed order: x y z
// (float, or double with positions_as_double), nx ny nz float, intensity float, profile int,
// column int, timestamp double, each only when the cloud has it; PLY faces as
// "property list uchar int vertex_indices". Binary bodies are laid out in one preallocated
// buffer with memcpy stores; ASCII numbers use std::to_chars (shortest text that reads back to
// the same float/double).
#include <string>

#include "core/io/codec.hpp"
#include "core/io/point_cloud_io.hpp"

namespace lasercell::io {
namespace detail {
namespace {

std::string PlyHeaderText(const PointCloud& cloud, std::size_t face_count,
                          const VertexLayout& layout, PlyEncoding encoding) {
  std::string h = "ply\nformat ";
  h += encoding == PlyEncoding::kAscii             ? "ascii"
       : encoding == PlyEncoding::kBinaryBigEndian ? "binary_big_endian"
                                                   : "binary_little_endian";
  h += " 1.0\ncomment lasercell_format 1\n";
  if (cloud.grid_rows > 0 && cloud.grid_cols > 0) {
    h += "comment lasercell_grid " + std::to_string(cloud.grid_rows) + " " +
         std::to_string(cloud.grid_cols) + "\n";
  }
  h += "element vertex " + std::to_string(cloud.size()) + "\n";
  const char* position_type = layout.double_positions ? "double" : "float";
  for (const char* axis : {"x", "y", "z"}) {
    h += std::string("property ") + position_type + " " + axis + "\n";
  }
  if (layout.normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (layout.intensity) h += "property float intensity\n";
  if (layout.profile) h += "property int profile\n";
  if (layout.column) h += "property int column\n";
  if (layout.timestamp) h += "property double timestamp\n";
  if (face_count > 0) {
    h +=
        "element face " + std::to_string(face_count) + "\nproperty list uchar int vertex_indices\n";
  }
  h += "end_header\n";
  return h;
}

}  // namespace

void AppendBinaryVertices(std::string& out, const PointCloud& cloud, const VertexLayout& layout,
                          bool swap) {
  const std::size_t start = out.size();
  out.resize(start + cloud.size() * layout.Stride());
  char* p = out.data() + start;
  auto put = [&p, swap](auto value) {
    StoreRaw(p, value, swap);
    p += sizeof(value);
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d& x = cloud.positions[i];
    for (int k = 0; k < 3; ++k) {
      if (layout.double_positions) {
        put(x[k]);
      } else {
        put(static_cast<float>(x[k]));
      }
    }
    if (layout.normals) {
      for (int k = 0; k < 3; ++k) put(static_cast<float>(cloud.normals[i][k]));
    }
    if (layout.intensity) put(cloud.intensity[i]);
    if (layout.profile) put(cloud.profile[i]);
    if (layout.column) put(cloud.column[i]);
    if (layout.timestamp) put(cloud.timestamp_s[i]);
  }
}

void AppendAsciiVertices(std::string& out, const PointCloud& cloud, const VertexLayout& layout) {
  out.reserve(out.size() + cloud.size() * 12 * (6 + (layout.normals ? 3 : 0)));
  auto field = [&out](auto value) {
    out += ' ';
    AppendNumber(out, value);
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d& x = cloud.positions[i];
    if (layout.double_positions) {
      AppendNumber(out, x[0]);
      field(x[1]);
      field(x[2]);
    } else {
      AppendNumber(out, static_cast<float>(x[0]));
      field(static_cast<float>(x[1]));
      field(static_cast<float>(x[2]));
    }
    if (layout.normals) {
      for (int k = 0; k < 3; ++k) field(static_cast<float>(cloud.normals[i][k]));
    }
    if (layout.intensity) field(cloud.intensity[i]);
    if (layout.profile) field(std::int64_t{cloud.profile[i]});
    if (layout.column) field(std::int64_t{cloud.column[i]});
    if (layout.timestamp) field(cloud.timestamp_s[i]);
    out += '\n';
  }
}

std::string EncodePlyUnchecked(const PointCloud& cloud, std::span<const Eigen::Vector3i> faces,
                               const WriteOptions& options) {
  const VertexLayout layout(cloud, options);
  std::string out = PlyHeaderText(cloud, faces.size(), layout, options.ply_encoding);
  if (options.ply_encoding == PlyEncoding::kAscii) {
    AppendAsciiVertices(out, cloud, layout);
    for (const Eigen::Vector3i& f : faces) {
      out += '3';
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        AppendNumber(out, std::int64_t{f[k]});
      }
      out += '\n';
    }
    return out;
  }
  const bool swap =
      options.ply_encoding == PlyEncoding::kBinaryBigEndian ? SwapFromBig() : SwapFromLittle();
  AppendBinaryVertices(out, cloud, layout, swap);
  std::size_t at = out.size();
  out.resize(at + faces.size() * 13);
  for (const Eigen::Vector3i& f : faces) {
    out[at++] = 3;
    for (int k = 0; k < 3; ++k, at += 4) StoreRaw<std::int32_t>(out.data() + at, f[k], swap);
  }
  return out;
}

}  // namespace detail

std::string EncodePly(const TriangleMesh& mesh, const WriteOptions& options) {
  detail::CheckWritable(mesh.vertices, mesh.faces, options, "mesh to encode as PLY");
  return detail::EncodePlyUnchecked(mesh.vertices, mesh.faces, options);
}

}  // namespace lasercell::io
