// lasercell.PointCloud: the C++ PointCloud (core/point_cloud.hpp) behind read-only NumPy views.
// A cloud is immutable from Python: its arrays are views into the C++ storage (no copy), marked
// read-only so that lasercell's invariants (finite positions, attributes one per point) hold;
// build a new cloud to change one (PointCloud(positions=..., normals=...) copies its inputs).
#include "core/point_cloud.hpp"

#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>

#include "core/io/point_cloud_io.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

constexpr std::size_t kAnySize = static_cast<std::size_t>(-1);

using CloudPtr = std::shared_ptr<PointCloud>;  // immutable from Python: no setter is bound

// The cloud from arrays; UnitError when the extent looks like metres (core/io's rule) unless
// `allow_small_extent`.
CloudPtr MakeCloud(const py::handle& positions, const py::object& normals,
                   const py::object& intensity, const py::object& profile, const py::object& column,
                   const py::object& timestamp_s, const std::optional<std::pair<int, int>>& grid,
                   bool allow_small_extent) {
  auto cloud = std::make_shared<PointCloud>();
  BoundingBox bounds;
  cloud->positions = ToVector3Rows(positions, "positions", true, &bounds);
  const std::size_t n = cloud->size();
  if (!normals.is_none()) {
    cloud->normals = ToVector3Rows(normals, "normals");
    if (cloud->normals.size() != n) {
      ThrowInput("normals: expected " + std::to_string(n) + " rows (one per position), got " +
                 std::to_string(cloud->normals.size()));
    }
  }
  if (!intensity.is_none()) cloud->intensity = ToFloats(intensity, "intensity", n);
  if (!profile.is_none()) cloud->profile = ToInt32s(profile, "profile", n);
  if (!column.is_none()) cloud->column = ToInt32s(column, "column", n);
  if (!timestamp_s.is_none()) cloud->timestamp_s = ToDoubles(timestamp_s, "timestamp_s", n);
  if (grid) {
    if (grid->first <= 0 || grid->second <= 0) {
      ThrowInput("grid: expected (rows, cols) both > 0, got (" + std::to_string(grid->first) +
                 ", " + std::to_string(grid->second) + ")");
    }
    cloud->grid_rows = grid->first;
    cloud->grid_cols = grid->second;
  }
  cloud->ValidateAttributes("PointCloud");  // ToVector3Rows checked the positions
  if (!allow_small_extent) {
    const std::string hint = io::UnitHint(bounds, n);
    if (!hint.empty()) {
      ThrowUnit("positions: " + hint + "; pass allow_small_extent=True if it really is mm");
    }
  }
  return cloud;
}

template <typename T>
py::object View(const std::vector<T>& values, const py::object& owner) {
  if (values.empty()) return py::none();
  return ReadOnlyView(values.data(), values.size(), 1, owner);
}

py::object RowsView(const std::vector<Eigen::Vector3d>& rows, const py::object& owner) {
  return rows.empty() ? py::none() : Vector3View(rows, owner);
}

io::PlyEncoding Encoding(const std::string& name) {
  if (name == "binary_little_endian") return io::PlyEncoding::kBinaryLittleEndian;
  if (name == "binary_big_endian") return io::PlyEncoding::kBinaryBigEndian;
  if (name == "ascii") return io::PlyEncoding::kAscii;
  ThrowInput(
      "ply_encoding: expected 'binary_little_endian', 'binary_big_endian' or 'ascii', got '" +
      name + "'");
}

void BindReadReport(py::module_& m) {
  py::class_<io::ReadReport>(m, "ReadReport", LC_DOC(io_ReadReport))
      .def_readonly("format", &io::ReadReport::format, LC_DOC(io_ReadReport_format))
      .def_readonly("points_in_file", &io::ReadReport::points_in_file,
                    LC_DOC(io_ReadReport_points_in_file))
      .def_readonly("dropped_non_finite", &io::ReadReport::dropped_non_finite,
                    LC_DOC(io_ReadReport_dropped_non_finite))
      .def_readonly("faces", &io::ReadReport::faces, LC_DOC(io_ReadReport_faces))
      .def_readonly("dropped_faces", &io::ReadReport::dropped_faces,
                    LC_DOC(io_ReadReport_dropped_faces))
      .def_readonly("fields_in_file", &io::ReadReport::fields_in_file,
                    LC_DOC(io_ReadReport_fields_in_file))
      .def_readonly("ignored_fields", &io::ReadReport::ignored_fields,
                    LC_DOC(io_ReadReport_ignored_fields))
      .def_readonly("lasercell_format_version", &io::ReadReport::lasercell_format_version,
                    LC_DOC(io_ReadReport_lasercell_format_version))
      .def_readonly("unit_hint", &io::ReadReport::unit_hint, LC_DOC(io_ReadReport_unit_hint))
      .def_readonly("notes", &io::ReadReport::notes, LC_DOC(io_ReadReport_notes));
}

}  // namespace

void BindPointCloud(py::module_& m) {
  BindReadReport(m);
  py::class_<PointCloud, CloudPtr>(m, "PointCloud", LC_DOC(core_PointCloud) R"doc(

In Python: arrays are read-only views into lasercell's storage (no copy); absent attributes
are None. Construct from arrays of any real dtype and memory order (they are copied).)doc")
      .def(py::init(&MakeCloud), py::arg("positions"), py::arg("normals") = py::none(),
           py::arg("intensity") = py::none(), py::arg("profile") = py::none(),
           py::arg("column") = py::none(), py::arg("timestamp_s") = py::none(),
           py::arg("grid") = py::none(), py::arg("allow_small_extent") = false,
           R"doc(Copies the arrays into a new cloud.

positions: (N, 3), mm, finite. normals: (N, 3) unit vectors. intensity, timestamp_s: (N,).
profile, column: (N,) integers, the grid cell of each point of an organized sweep, with
grid=(rows, cols). Raises TypeError for a non-numeric array, lasercell.InputError for a wrong
shape or a NaN/inf value, lasercell.UnitError when the extent (under 10) suggests metres.)doc")
      .def("__len__", &PointCloud::size, LC_DOC(core_PointCloud_size))
      .def_property_readonly(
          "positions",
          [](const py::object& self) {
            return RowsView(self.cast<const PointCloud&>().positions, self);
          },
          "(N, 3) float64, mm.")
      .def_property_readonly(
          "normals",
          [](const py::object& self) {
            return RowsView(self.cast<const PointCloud&>().normals, self);
          },
          "(N, 3) float64 unit normals, or None.")
      .def_property_readonly(
          "intensity",
          [](const py::object& self) {
            return View(self.cast<const PointCloud&>().intensity, self);
          },
          "(N,) float32, or None.")
      .def_property_readonly(
          "profile",
          [](const py::object& self) { return View(self.cast<const PointCloud&>().profile, self); },
          "(N,) int32 grid row (sweep profile), or None.")
      .def_property_readonly(
          "column",
          [](const py::object& self) { return View(self.cast<const PointCloud&>().column, self); },
          "(N,) int32 grid column, or None.")
      .def_property_readonly(
          "timestamp_s",
          [](const py::object& self) {
            return View(self.cast<const PointCloud&>().timestamp_s, self);
          },
          "(N,) float64 acquisition time, s, or None.")
      .def_property_readonly(
          "grid",
          [](const PointCloud& c) -> py::object {
            if (c.grid_rows <= 0 || c.grid_cols <= 0) return py::none();
            return py::make_tuple(c.grid_rows, c.grid_cols);
          },
          "(rows, cols) of an organized cloud, or None.")
      .def_property_readonly("is_organized", &PointCloud::IsOrganized,
                             LC_DOC(core_PointCloud_IsOrganized))
      .def_property_readonly("field_names", &PointCloud::FieldNames,
                             LC_DOC(core_PointCloud_FieldNames))
      .def(
          "transformed",
          [](const PointCloud& c, const py::handle& target_from_source) {
            return std::make_shared<PointCloud>(
                c.Transformed(ToIsometry(target_from_source, "target_from_source")));
          },
          py::arg("target_from_source"),
          "A copy with positions and normals moved by a 4x4 rigid transform.")
      .def("__repr__", [](const PointCloud& c) {
        return "<lasercell.PointCloud " + std::to_string(c.size()) + " points: " + c.FieldNames() +
               ">";
      });

  m.def(
      "read_point_cloud",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return std::make_shared<PointCloud>(io::ReadPointCloud(path));
      },
      py::arg("path"), "Reads a .ply or .pcd; raises lasercell.FileError naming the problem.");
  m.def(
      "read_point_cloud_with_report",
      [](const std::string& path) {
        io::ReadReport report;
        CloudPtr cloud;
        {
          py::gil_scoped_release release;
          cloud = std::make_shared<PointCloud>(io::ReadPointCloud(path, &report));
        }
        return py::make_tuple(cloud, report);
      },
      py::arg("path"), "(cloud, ReadReport) of a .ply or .pcd.");
  m.def(
      "write_point_cloud",
      [](const std::string& path, const PointCloud& cloud, const std::string& ply_encoding,
         bool pcd_binary, bool positions_as_double) {
        io::WriteOptions options;
        options.ply_encoding = Encoding(ply_encoding);
        options.pcd_binary = pcd_binary;
        options.positions_as_double = positions_as_double;
        py::gil_scoped_release release;
        io::WritePointCloud(path, cloud, options);
      },
      py::arg("path"), py::arg("cloud"), py::arg("ply_encoding") = "binary_little_endian",
      py::arg("pcd_binary") = true, py::arg("positions_as_double") = false,
      "Writes .ply or .pcd (by extension), atomically.");
}

}  // namespace lasercell::python
