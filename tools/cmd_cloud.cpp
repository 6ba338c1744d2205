// `lasercell cloud info FILE` and `lasercell cloud convert IN OUT`.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

void PrintInfo(const std::string& path) {
  io::ReadReport report;
  const TriangleMesh mesh = io::LowerExtension(path) == ".ply"
                                ? io::ReadPlyMesh(path, &report)
                                : TriangleMesh{io::ReadPointCloud(path, &report), {}};
  const PointCloud& cloud = mesh.vertices;
  const BoundingBox box = cloud.Bounds();
  std::printf("file: %s\n", path.c_str());
  std::printf("format: %s", report.format.c_str());
  if (report.lasercell_format_version > 0) {
    std::printf(" (lasercell format %d)", report.lasercell_format_version);
  }
  std::printf("\npoints: %zu", cloud.size());
  if (report.dropped_non_finite > 0) {
    std::printf(" (%zu of %zu in the file dropped: non-finite coordinates or normals)",
                report.dropped_non_finite, report.points_in_file);
  }
  std::printf("\n");
  if (!mesh.faces.empty()) std::printf("faces: %zu\n", mesh.faces.size());
  std::printf("fields: %s\n", cloud.FieldNames().c_str());
  if (!report.ignored_fields.empty()) {
    std::string ignored;
    for (const auto& f : report.ignored_fields) ignored += (ignored.empty() ? "" : " ") + f;
    std::printf("ignored fields: %s\n", ignored.c_str());
  }
  if (cloud.IsOrganized()) {
    std::printf("organized: yes, %d rows x %d columns (%zu of %lld cells valid)\n", cloud.grid_rows,
                cloud.grid_cols, cloud.size(),
                static_cast<long long>(cloud.grid_rows) * cloud.grid_cols);
  } else {
    std::printf("organized: no\n");
  }
  if (box.Empty()) {
    std::printf("bounding box: empty\n");
  } else {
    const Eigen::Vector3d size = box.Size();
    std::printf("bounding box min: [%.4f, %.4f, %.4f]\n", box.min.x(), box.min.y(), box.min.z());
    std::printf("bounding box max: [%.4f, %.4f, %.4f]\n", box.max.x(), box.max.y(), box.max.z());
    std::printf("extent: %.4f x %.4f x %.4f (diagonal %.4f)\n", size.x(), size.y(), size.z(),
                box.Diagonal());
  }
  std::printf("units: %s\n", report.unit_hint.empty()
                                 ? "millimetres assumed (lasercell works in mm)"
                                 : report.unit_hint.c_str());
}

struct ConvertArgs {
  std::string in, out;
  double scale = 1.0;
  bool ascii = false;
  bool big_endian = false;
  bool as_double = false;
};

void Convert(const ConvertArgs& args) {
  if (!(args.scale > 0) || !std::isfinite(args.scale)) {
    throw InputError("--scale " + std::to_string(args.scale) + ": must be a positive number");
  }
  const std::string in_ext = io::LowerExtension(args.in);
  const std::string out_ext = io::LowerExtension(args.out);
  if (out_ext != ".ply" && out_ext != ".pcd") {
    throw FileError(args.out, "unknown output type '" + out_ext + "'; use .ply or .pcd");
  }
  io::ReadReport report;
  TriangleMesh mesh = in_ext == ".ply" ? io::ReadPlyMesh(args.in, &report)
                                       : TriangleMesh{io::ReadPointCloud(args.in, &report), {}};
  if (args.scale != 1.0) {
    for (auto& p : mesh.vertices.positions) p *= args.scale;
  }
  io::WriteOptions options;
  options.ply_encoding = args.ascii        ? io::PlyEncoding::kAscii
                         : args.big_endian ? io::PlyEncoding::kBinaryBigEndian
                                           : io::PlyEncoding::kBinaryLittleEndian;
  options.pcd_binary = !args.ascii;
  options.positions_as_double = args.as_double;
  if (out_ext == ".ply") {
    io::WritePlyMesh(args.out, mesh, options);
  } else {
    if (!mesh.faces.empty()) {
      std::fprintf(stderr, "note: %zu faces not written (PCD holds points only)\n",
                   mesh.faces.size());
    }
    io::WritePointCloud(args.out, mesh.vertices, options);
  }
  std::printf("wrote %s: %zu points%s\n", args.out.c_str(), mesh.vertices.size(),
              report.dropped_non_finite > 0 ? (" (" + std::to_string(report.dropped_non_finite) +
                                               " non-finite points of the input dropped)")
                                                  .c_str()
                                            : "");
}

}  // namespace

void AddCloudCommands(CLI::App& app) {
  CLI::App* cloud = app.add_subcommand("cloud", "Inspect and convert point clouds (PLY, PCD)");
  cloud->require_subcommand(1);

  CLI::App* info = cloud->add_subcommand("info", "Print point count, fields, bounding box, grid");
  auto info_path = std::make_shared<std::string>();
  info->add_option("FILE", *info_path, "PLY or PCD file")->required();
  info->callback([info_path] { PrintInfo(*info_path); });

  CLI::App* convert =
      cloud->add_subcommand("convert", "Convert between PLY and PCD (binary by default)");
  auto args = std::make_shared<ConvertArgs>();
  convert->add_option("IN", args->in, "Input PLY or PCD")->required();
  convert->add_option("OUT", args->out, "Output .ply or .pcd (written atomically)")->required();
  convert->add_option("--scale", args->scale,
                      "Multiply coordinates, e.g. 1000 for metres -> millimetres");
  convert->add_flag("--ascii", args->ascii, "Write ASCII instead of binary");
  convert->add_flag("--big-endian", args->big_endian, "Binary PLY big endian");
  convert->add_flag("--double", args->as_double, "Store positions as float64");
  convert->callback([args] { Convert(*args); });
}

}  // namespace lasercell::tools
