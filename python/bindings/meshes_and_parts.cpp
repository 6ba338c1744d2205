// Part models from Python: triangle meshes (STL, OBJ, PLY: core/io/mesh_io.hpp), CAD files
// (STEP, IGES through OpenCASCADE: localize/cad_import.hpp) and part files (localize/part.hpp:
// the model, grasp frames, stable poses, symmetry).
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/io/mesh_io.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "localize/cad_import.hpp"
#include "localize/part.hpp"
#include "python/bindings/bindings.hpp"
#include "registration/normals.hpp"

namespace lasercell::python {
namespace {

using MeshPtr = std::shared_ptr<TriangleMesh>;

// A mesh from vertices (a PointCloud, or an (N, 3) array of positions in mm) and (M, 3)
// integer faces; InputError naming the argument for a bad shape or a face index out of range.
MeshPtr MakeMesh(const py::object& vertices, const py::handle& faces) {
  auto mesh = std::make_shared<TriangleMesh>();
  if (py::isinstance<PointCloud>(vertices)) {
    mesh->vertices = vertices.cast<const PointCloud&>();
  } else {
    mesh->vertices.positions = ToVector3Rows(vertices, "vertices");
  }
  const py::array a = py::array::ensure(faces);
  if (!a || a.ndim() != 2 || a.shape(1) != 3) {
    ThrowInput("faces: expected an (M, 3) integer array of vertex indices");
  }
  const auto m = static_cast<std::size_t>(a.shape(0));
  const std::vector<std::int32_t> flat = ToInt32s(a.attr("reshape")(-1), "faces", 3 * m);
  const auto n = static_cast<std::int64_t>(mesh->vertices.size());
  mesh->faces.resize(m);
  for (std::size_t f = 0; f < m; ++f) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t index = flat[3 * f + k];
      if (index < 0 || index >= n) {
        ThrowInput("faces: row " + std::to_string(f) + " names vertex " + std::to_string(index) +
                   " but there are " + std::to_string(n) + " vertices");
      }
      mesh->faces[f][k] = index;
    }
  }
  return mesh;
}

void BindMesh(py::module_& m) {
  py::class_<TriangleMesh, MeshPtr>(m, "TriangleMesh", LC_DOC(core_TriangleMesh))
      .def(py::init(&MakeMesh), py::arg("vertices"), py::arg("faces"),
           "vertices: a PointCloud or (N, 3) positions, mm; faces: (M, 3) integer vertex "
           "indices, counter-clockwise seen from outside.")
      .def_property_readonly(
          "vertices",
          [](const MeshPtr& mesh) { return std::shared_ptr<PointCloud>(mesh, &mesh->vertices); },
          "The vertices as a PointCloud (positions, and normals when known).")
      .def_property_readonly(
          "faces", [](const TriangleMesh& mesh) { return RowsArray(mesh.faces); },
          "(M, 3) int32 vertex indices, counter-clockwise seen from outside.")
      .def("__repr__", [](const TriangleMesh& mesh) {
        return "<lasercell.TriangleMesh " + std::to_string(mesh.vertices.size()) + " vertices, " +
               std::to_string(mesh.faces.size()) + " faces>";
      });
  m.def(
      "read_mesh",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return std::make_shared<TriangleMesh>(io::ReadMesh(path));
      },
      py::arg("path"), "Reads an STL (binary or ASCII), OBJ or PLY mesh; FileError naming it.");
  m.def(
      "write_mesh",
      [](const std::string& path, const TriangleMesh& mesh) {
        py::gil_scoped_release release;
        io::WriteMesh(path, mesh);
      },
      py::arg("path"), py::arg("mesh"), LC_DOC(io_WriteMesh));
  m.def(
      "mesh_vertex_normals",
      [](const TriangleMesh& mesh) { return RowsArray(registration::MeshVertexNormals(mesh)); },
      py::arg("mesh"), LC_DOC(registration_MeshVertexNormals) " Returned as an (N, 3) array.");
  m.def(
      "with_mesh_normals",
      [](const TriangleMesh& mesh) {
        std::size_t dropped = 0;
        auto cloud = std::make_shared<PointCloud>(registration::WithMeshNormals(mesh, &dropped));
        return py::make_tuple(cloud, dropped);
      },
      py::arg("mesh"), LC_DOC(registration_WithMeshNormals) " Returns (PointCloud, dropped).");
}

void BindCad(py::module_& m) {
  py::class_<localize::CadModel, std::shared_ptr<localize::CadModel>>(
      m, "CadModel", "A part read from STEP or IGES, in mm.")
      .def_property_readonly(
          "mesh", [](const std::shared_ptr<localize::CadModel>& c) { return MeshPtr(c, &c->mesh); },
          "The tessellated boundary with outward vertex normals from the exact surfaces.")
      .def_property_readonly(
          "samples",
          [](const std::shared_ptr<localize::CadModel>& c) {
            return std::shared_ptr<PointCloud>(c, &c->samples);
          },
          "Oriented points sampled on the exact faces (outward unit normals).")
      .def_readonly("format", &localize::CadModel::format, LC_DOC(localize_CadModel_format))
      .def_readonly("source_unit", &localize::CadModel::source_unit,
                    LC_DOC(localize_CadModel_source_unit))
      .def_readonly("scale_to_mm", &localize::CadModel::scale_to_mm,
                    LC_DOC(localize_CadModel_scale_to_mm))
      .def_readonly("solids", &localize::CadModel::solids, LC_DOC(localize_CadModel_solids))
      .def_readonly("faces", &localize::CadModel::faces, LC_DOC(localize_CadModel_faces))
      .def_readonly("surface_area_mm2", &localize::CadModel::surface_area_mm2,
                    LC_DOC(localize_CadModel_surface_area_mm2));
  m.def(
      "read_cad_model",
      [](const std::string& path, double sampling_step_mm, double linear_deflection_mm,
         double timeout_s) {
        localize::CadImportOptions options;
        options.sampling_step_mm = sampling_step_mm;
        options.linear_deflection_mm = linear_deflection_mm;
        options.timeout_s = timeout_s;
        options.Check();
        py::gil_scoped_release release;
        return std::make_shared<localize::CadModel>(localize::ReadCadModel(path, options));
      },
      py::arg("path"), py::arg("sampling_step_mm") = 1.0, py::arg("linear_deflection_mm") = 0.05,
      py::arg("timeout_s") = 600.0,
      "Reads STEP (.step/.stp) or IGES (.iges/.igs) through OpenCASCADE, converted to mm: "
      "tessellated mesh and oriented samples. InputError/FileError naming the file.");
}

void BindPart(py::module_& m) {
  py::class_<localize::PartDefinition>(m, "Part", LC_DOC(localize_PartDefinition))
      .def_static("load", &localize::ReadPartFile, py::arg("path"), LC_DOC(localize_ReadPartFile))
      .def_readonly("name", &localize::PartDefinition::name, LC_DOC(localize_PartDefinition_name))
      .def_readonly("model_path", &localize::PartDefinition::model_path,
                    LC_DOC(localize_PartDefinition_model_path))
      .def_readonly("units", &localize::PartDefinition::units,
                    LC_DOC(localize_PartDefinition_units))
      .def_property_readonly(
          "grasps",
          [](const localize::PartDefinition& p) {
            py::dict out;
            for (const localize::GraspFrame& g : p.grasps) {
              out[py::str(g.name)] = FromIsometry(g.part_from_grasp.ToIsometry());
            }
            return out;
          },
          "{grasp name: 4x4 part_from_grasp}.")
      .def_property_readonly(
          "stable_up_in_part",
          [](const localize::PartDefinition& p) {
            py::list out;
            for (const Eigen::Vector3d& v : p.stable_up_in_part) {
              out.append(py::array_t<double>(3, v.data()));
            }
            return out;
          },
          "Unit axes of the stable poses (empty: any orientation).")
      .def_readonly("max_tilt_rad", &localize::PartDefinition::max_tilt_rad,
                    LC_DOC(localize_PartDefinition_max_tilt_rad))
      .def_static("from_yaml", &localize::ParsePartFile, py::arg("text"), py::arg("path"),
                  LC_DOC(localize_ParsePartFile))
      .def("to_yaml", &localize::PartFileYaml, LC_DOC(localize_PartFileYaml))
      .def(
          "save",
          [](const localize::PartDefinition& p, const std::string& path) {
            localize::WritePartFile(path, p);
          },
          py::arg("path"),
          "Writes the part file atomically (model as written: relative to the part file).")
      .def(
          "set_grasp",
          [](localize::PartDefinition& p, const std::string& name, const py::handle& pose,
             const std::string& description) {
            localize::GraspFrame grasp;
            grasp.name = name;
            grasp.part_from_grasp =
                QuaternionPose::FromIsometry(ToIsometry(pose, "part_from_grasp"));
            grasp.description = description;
            localize::PartDefinition changed = p;
            auto same = [&](const localize::GraspFrame& g) { return g.name == name; };
            changed.grasps.erase(std::remove_if(changed.grasps.begin(), changed.grasps.end(), same),
                                 changed.grasps.end());
            changed.grasps.push_back(grasp);
            changed.Check();  // a bad name raises before the part changes
            p = std::move(changed);
          },
          py::arg("name"), py::arg("part_from_grasp"), py::arg("description") = "",
          "Adds or replaces a grasp frame (4x4 part_from_grasp, mm).")
      .def("__repr__", [](const localize::PartDefinition& p) {
        return "<lasercell.Part " + p.name + ": " + p.model + ", " +
               std::to_string(p.grasps.size()) + " grasp(s)>";
      });
}

}  // namespace

void BindMeshesAndParts(py::module_& m) {
  BindMesh(m);
  BindCad(m);
  BindPart(m);
}

}  // namespace lasercell::python
