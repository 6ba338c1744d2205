// lasercell.FrameGraph: the cell's frame graph (core/frame_graph.hpp), loaded from and saved to
// cell.yaml; transforms as 4x4 float64 arrays (target_from_source, mm), with the first-order
// covariance over [rotation vector (rad); translation (mm)].
#include "core/frame_graph.hpp"

#include <pybind11/stl.h>

#include <map>
#include <string>
#include <vector>

#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

// {"robot": [q1, q2, ...]} with the values as any real sequence or 1-D array.
JointValues ToJoints(const py::object& joints) {
  JointValues out;
  if (joints.is_none()) return out;
  if (!py::isinstance<py::dict>(joints)) {
    throw py::type_error("joints: expected a dict {robot name: joint values (rad or mm)}");
  }
  for (const auto& [key, value] : joints.cast<py::dict>()) {
    const std::string robot = py::str(key);
    out[robot] = ToDoubles(value, "joints['" + robot + "']", static_cast<std::size_t>(-1));
  }
  return out;
}

py::array_t<double> Matrix6(const Matrix6d& m) {
  py::array_t<double> out({6, 6});
  auto view = out.mutable_unchecked<2>();
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) view(r, c) = m(r, c);
  }
  return out;
}

}  // namespace

void BindFrameGraph(py::module_& m) {
  py::class_<TransformWithCovarianceResult>(
      m, "TransformWithCovariance",
      "A transform with its first-order covariance and what that covariance leaves out.")
      .def_property_readonly(
          "to_from_from",
          [](const TransformWithCovarianceResult& r) { return FromIsometry(r.to_from_from); },
          "4x4 float64, mm.")
      .def_property_readonly(
          "covariance",
          [](const TransformWithCovarianceResult& r) { return Matrix6(r.covariance); },
          "6x6 over [rotation vector (rad); translation (mm)], left "
          "perturbation in the `to` frame.")
      .def_readonly("edges_without_covariance",
                    &TransformWithCovarianceResult::edges_without_covariance)
      .def_readonly("crosses_dynamic_edge", &TransformWithCovarianceResult::crosses_dynamic_edge)
      .def_readonly("robots_on_path", &TransformWithCovarianceResult::robots_on_path)
      .def_property_readonly("complete", &TransformWithCovarianceResult::Complete)
      .def("summary", &TransformWithCovarianceResult::Summary);

  py::class_<FrameGraph>(m, "FrameGraph",
                         "The cell's named frames joined by static and robot "
                         "edges (cell.yaml).")
      .def(py::init<>())
      .def_static("load", &LoadFrameGraph, py::arg("path"),
                  "Reads cell.yaml; raises lasercell.FileError naming the problem.")
      .def_static("from_yaml", &FrameGraphFromYaml, py::arg("text"), py::arg("name") = "cell.yaml",
                  "Parses cell.yaml text.")
      .def(
          "save", [](const FrameGraph& g, const std::string& path) { SaveFrameGraph(path, g); },
          py::arg("path"), "Writes cell.yaml atomically.")
      .def("to_yaml", &FrameGraphToYaml)
      .def_property_readonly("frames", &FrameGraph::Frames)
      .def_property_readonly("robots", &FrameGraph::Robots)
      .def("has_frame", &FrameGraph::HasFrame, py::arg("name"))
      .def("connected", &FrameGraph::Connected, py::arg("a"), py::arg("b"))
      .def("robots_on_path", &FrameGraph::RobotsOnPath, py::arg("to"), py::arg("from_"))
      .def(
          "transform",
          [](const FrameGraph& g, const std::string& to, const std::string& from,
             const py::object& joints) {
            return FromIsometry(g.Transform(to, from, ToJoints(joints)));
          },
          py::arg("to"), py::arg("from_"), py::arg("joints") = py::none(),
          R"doc(to_from_from as a 4x4 float64 array (p_to = T @ p_from, mm).

joints: {robot: joint values} for every robot edge on the path. Raises lasercell.InputError
for unknown or unconnected frames, or missing joint values.)doc")
      .def(
          "transform_with_covariance",
          [](const FrameGraph& g, const std::string& to, const std::string& from,
             const py::object& joints) {
            return g.TransformWithCovariance(to, from, ToJoints(joints));
          },
          py::arg("to"), py::arg("from_"), py::arg("joints") = py::none(),
          "transform() with its covariance (TransformWithCovariance).")
      .def("__repr__", [](const FrameGraph& g) {
        return "<lasercell.FrameGraph " + std::to_string(g.Frames().size()) + " frames, " +
               std::to_string(g.Robots().size()) + " robots>";
      });
}

}  // namespace lasercell::python
