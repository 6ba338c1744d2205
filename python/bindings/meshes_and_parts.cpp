// Part models from Python: triangle meshes (STL, OBJ, PLY: core/io/mesh_io.hpp), CAD files
// (STEP, IGES through OpenCASCADE: localize/cad_import.hpp) and part files (localize/part.hpp:
// the model, grasp frames, stable poses, symmetry).
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include "core/io/mesh_io.hpp"
#include "localize/cad_import.hpp"
#include "localize/part.hpp"
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

using MeshPtr = std::shared_ptr<TriangleMesh>;

void BindMesh(py::module_& m) {
  py::class_<TriangleMesh, MeshPtr>(m, "TriangleMesh", "A triangle mesh in mm.")
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
      .def_readonly("format", &localize::CadModel::format)
      .def_readonly("source_unit", &localize::CadModel::source_unit)
      .def_readonly("scale_to_mm", &localize::CadModel::scale_to_mm)
      .def_readonly("solids", &localize::CadModel::solids)
      .def_readonly("faces", &localize::CadModel::faces)
      .def_readonly("surface_area_mm2", &localize::CadModel::surface_area_mm2);
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
  py::class_<localize::PartDefinition>(m, "Part", "A part file: model, grasp frames, stable poses.")
      .def_static("load", &localize::ReadPartFile, py::arg("path"),
                  "Reads a part file (format lasercell.part); OptionError names file and field.")
      .def_readonly("name", &localize::PartDefinition::name)
      .def_readonly("model_path", &localize::PartDefinition::model_path, "Resolved.")
      .def_readonly("units", &localize::PartDefinition::units)
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
      .def_readonly("max_tilt_rad", &localize::PartDefinition::max_tilt_rad)
      .def("to_yaml", &localize::PartFileYaml, "The part file text.")
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
