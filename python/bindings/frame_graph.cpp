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
          [](const TransformWithCovarianceResult& r) { return FromMatrix(r.covariance); },
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
      .def(
          "set_static_edge",
          [](FrameGraph& g, const std::string& parent, const std::string& child,
             const py::handle& parent_from_child, const py::object& covariance,
             const std::string& tool) {
            StaticEdge edge;
            edge.parent = parent;
            edge.child = child;
            edge.SetParentFromChild(ToIsometry(parent_from_child, "parent_from_child"));
            edge.provenance.tool = tool;
            if (!covariance.is_none()) {
              const std::vector<double> c =
                  ToDoubles(py::array::ensure(covariance).attr("reshape")(-1), "covariance", 36);
              edge.covariance = Eigen::Map<const Matrix6d>(c.data()).transpose();
            }
            g.SetStaticEdge(edge);
          },
          py::arg("parent"), py::arg("child"), py::arg("parent_from_child"),
          py::arg("covariance") = py::none(), py::arg("tool") = "python",
          "Adds or replaces a static edge (4x4, mm; covariance 6x6 over [rotation vector (rad); "
          "translation (mm)] or None). InputError when it would close a cycle.")
      .def("remove_edge", &FrameGraph::RemoveEdge, py::arg("a"), py::arg("b"),
           "Removes the edge between a and b; False when there was none.")
      .def(
          "set_laser_plane",
          [](FrameGraph& g, const std::string& name, const py::handle& normal,
             const py::handle& point_mm, const std::string& frame) {
            LaserPlaneEntry plane;
            plane.frame = frame;
            plane.normal = ToVector3(normal, "normal");
            plane.point_mm = ToVector3(point_mm, "point_mm");
            g.SetLaserPlane(name, plane);
          },
          py::arg("name"), py::arg("normal"), py::arg("point_mm"), py::arg("frame") = "sensor",
          "Adds or replaces a laser plane: unit normal and a point of it, mm, in `frame`.")
      .def_property_readonly(
          "laser_planes",
          [](const FrameGraph& g) {
            py::dict planes;
            for (const auto& [name, plane] : g.laser_planes()) {
              planes[py::str(name)] =
                  py::make_tuple(plane.frame, py::array_t<double>(3, plane.normal.data()),
                                 py::array_t<double>(3, plane.point_mm.data()));
            }
            return planes;
          },
          "{name: (frame, unit normal (3,), point (3,) mm)}.")
      .def("__repr__", [](const FrameGraph& g) {
        return "<lasercell.FrameGraph " + std::to_string(g.Frames().size()) + " frames, " +
               std::to_string(g.Robots().size()) + " robots>";
      });
}

}  // namespace lasercell::python
