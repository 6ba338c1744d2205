// PCD writer: "DATA binary" (default) or "DATA ascii", always unorganized (WIDTH = points,
// HEIGHT = 1) so that no NaN filler points are needed. Nothing is lost: profile and column are
// written as int fields of those names, timestamp as a float64 field, and the grid size as the
// comment "# lasercell_grid ROWS COLS" (PCL skips '#' lines; our reader restores the grid).
#include <string>

#include "core/io/codec.hpp"
#include "core/io/point_cloud_io.hpp"

namespace lasercell::io {
namespace detail {

std::string EncodePcdUnchecked(const PointCloud& cloud, const WriteOptions& options) {
  const VertexLayout layout(cloud, options);
  struct Field {
    const char* name;
    char type;
    int size;
  };
  std::vector<Field> fields;
  const int position_size = layout.double_positions ? 8 : 4;
  for (const char* axis : {"x", "y", "z"}) fields.push_back({axis, 'F', position_size});
  if (layout.normals) {
    for (const char* n : {"normal_x", "normal_y", "normal_z"}) fields.push_back({n, 'F', 4});
  }
  if (layout.intensity) fields.push_back({"intensity", 'F', 4});
  if (layout.profile) fields.push_back({"profile", 'I', 4});
  if (layout.column) fields.push_back({"column", 'I', 4});
  if (layout.timestamp) fields.push_back({"timestamp", 'F', 8});

  std::string out = "# .PCD v0.7 - Point Cloud Data file format\n# lasercell_format 1\n";
  if (cloud.grid_rows > 0 && cloud.grid_cols > 0) {
    out += "# lasercell_grid " + std::to_string(cloud.grid_rows) + " " +
           std::to_string(cloud.grid_cols) + "\n";
  }
  // Built with append rather than operator+ (GCC 12 -Wrestrict false positive on the latter).
  std::string names, sizes, types, counts;
  for (const Field& f : fields) {
    names.append(" ").append(f.name);
    sizes.append(" ").append(std::to_string(f.size));
    types.append(" ").push_back(f.type);
    counts.append(" 1");
  }
  const std::string n = std::to_string(cloud.size());
  out.append("VERSION 0.7\nFIELDS").append(names);
  out.append("\nSIZE").append(sizes).append("\nTYPE").append(types);
  out.append("\nCOUNT").append(counts).append("\nWIDTH ").append(n);
  out.append("\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS ").append(n);
  out.append("\nDATA ").append(options.pcd_binary ? "binary" : "ascii").append("\n");
  if (options.pcd_binary) {
    AppendBinaryVertices(out, cloud, layout, SwapFromLittle());  // PCD binary: little endian
  } else {
    AppendAsciiVertices(out, cloud, layout);
  }
  return out;
}

}  // namespace detail

std::string EncodePcd(const PointCloud& cloud, const WriteOptions& options) {
  detail::CheckWritable(cloud, {}, options, "cloud to encode as PCD");
  return detail::EncodePcdUnchecked(cloud, options);
}

}  // namespace lasercell::io
