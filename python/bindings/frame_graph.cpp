// lasercell.FrameGraph: the cell's frame graph (core/frame_graph.hpp), loaded from and saved to
// cell.yaml; transforms as 4x4 float64 arrays (target_from_source, mm), with the first-order
// covariance over [rotation vector (rad); translation (mm)].
#include "core/frame_graph.hpp"

#include <pybind11/stl.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/kinematics.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
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

DhConvention Convention(const std::string& name) {
  if (name == "standard") return DhConvention::kStandard;
  if (name == "modified") return DhConvention::kModified;
  ThrowInput("convention: expected 'standard' or 'modified', got '" + name + "'");
}

// DH rows [a_mm, alpha_rad, d_mm, theta_offset_rad (, joint_offset_rad)] from a (J, 4) or
// (J, 5) array.
std::vector<DhJoint> DhRows(const py::handle& dh) {
  const py::array a = py::array::ensure(dh);
  if (!a || a.ndim() != 2 || (a.shape(1) != 4 && a.shape(1) != 5) || a.shape(0) == 0) {
    ThrowInput(
        "dh: expected a (J, 4) or (J, 5) array of [a_mm, alpha_rad, d_mm, "
        "theta_offset_rad(, joint_offset_rad)] rows");
  }
  const auto cols = static_cast<std::size_t>(a.shape(1));
  const std::vector<double> v = ToDoubles(a.attr("reshape")(-1), "dh", a.shape(0) * cols);
  std::vector<DhJoint> joints(static_cast<std::size_t>(a.shape(0)));
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const double* row = &v[j * cols];
    joints[j] = {row[0], row[1], row[2], row[3], cols == 5 ? row[4] : 0.0};
  }
  return joints;
}

// Robot kinematics: a DH robot between two frames, and its table back.
void BindRobots(py::class_<FrameGraph>& graph) {
  graph.def(
      "set_dh_robot",
      [](FrameGraph& g, const std::string& robot, const std::string& base,
         const std::string& flange, const py::handle& dh, const std::string& convention,
         const py::object& base_from_chain, const py::object& chain_from_flange) {
        const Eigen::Isometry3d mount_base = base_from_chain.is_none()
                                                 ? Eigen::Isometry3d::Identity()
                                                 : ToIsometry(base_from_chain, "base_from_chain");
        const Eigen::Isometry3d mount_flange =
            chain_from_flange.is_none() ? Eigen::Isometry3d::Identity()
                                        : ToIsometry(chain_from_flange, "chain_from_flange");
        const DhChain chain(Convention(convention), DhRows(dh), mount_base, mount_flange);
        FrameGraph changed = g;  // a refused edge leaves the graph as it was
        changed.SetRobot(robot, chain);
        changed.SetDynamicEdge({base, flange, robot});
        g = std::move(changed);
      },
      py::arg("robot"), py::arg("base"), py::arg("flange"), py::arg("dh"),
      py::arg("convention") = "standard", py::arg("base_from_chain") = py::none(),
      py::arg("chain_from_flange") = py::none(),
      R"doc(Adds or replaces a robot given by its DH table and the dynamic edge base -> flange
that its joints drive. dh: (J, 4) or (J, 5) rows [a_mm, alpha_rad, d_mm, theta_offset_rad(,
joint_offset_rad)]; convention 'standard' (A = Rz(theta) Tz(d) Tx(a) Rx(alpha)) or 'modified'
(Craig); mounts 4x4, mm. InputError for a non-finite value or an edge closing a cycle.)doc");
  graph.def(
      "robot_dh",
      [](const FrameGraph& g, const std::string& robot) {
        const auto* chain = dynamic_cast<const DhChain*>(&g.Robot(robot));
        if (!chain) ThrowInput("robot '" + robot + "' is not a DH chain");
        std::vector<Eigen::Matrix<double, 5, 1>> rows;
        for (const DhJoint& j : chain->joints()) {
          rows.push_back((Eigen::Matrix<double, 5, 1>() << j.a_mm, j.alpha_rad, j.d_mm,
                          j.theta_offset_rad, j.joint_offset_rad)
                             .finished());
        }
        py::dict out;
        out["convention"] =
            chain->convention() == DhConvention::kStandard ? "standard" : "modified";
        out["dh"] = RowsArray(rows);
        out["base_from_chain"] = FromIsometry(chain->base_from_chain());
        out["chain_from_flange"] = FromIsometry(chain->chain_from_flange());
        return out;
      },
      py::arg("robot"),
      "{convention, dh: (J, 5) [a_mm, alpha_rad, d_mm, theta_offset_rad, joint_offset_rad], "
      "base_from_chain, chain_from_flange} of a DH robot; InputError for an unknown robot.");
}

}  // namespace

void BindFrameGraph(py::module_& m) {
  py::class_<TransformWithCovarianceResult>(m, "TransformWithCovariance",
                                            LC_DOC(core_TransformWithCovarianceResult))
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
                    &TransformWithCovarianceResult::edges_without_covariance,
                    LC_DOC(core_TransformWithCovarianceResult_edges_without_covariance))
      .def_readonly("crosses_dynamic_edge", &TransformWithCovarianceResult::crosses_dynamic_edge,
                    LC_DOC(core_TransformWithCovarianceResult_crosses_dynamic_edge))
      .def_readonly("robots_on_path", &TransformWithCovarianceResult::robots_on_path,
                    LC_DOC(core_TransformWithCovarianceResult_robots_on_path))
      .def_property_readonly("complete", &TransformWithCovarianceResult::Complete,
                             LC_DOC(core_TransformWithCovarianceResult_Complete))
      .def("summary", &TransformWithCovarianceResult::Summary,
           LC_DOC(core_TransformWithCovarianceResult_Summary));

  py::class_<FrameGraph> graph(m, "FrameGraph", LC_DOC(core_FrameGraph));
  BindRobots(graph);
  graph.def(py::init<>())
      .def_static("load", &LoadFrameGraph, py::arg("path"), LC_DOC(core_LoadFrameGraph))
      .def_static("from_yaml", &FrameGraphFromYaml, py::arg("text"), py::arg("name") = "cell.yaml",
                  LC_DOC(core_FrameGraphFromYaml))
      .def(
          "save", [](const FrameGraph& g, const std::string& path) { SaveFrameGraph(path, g); },
          py::arg("path"), "Writes cell.yaml atomically.")
      .def("to_yaml", &FrameGraphToYaml, LC_DOC(core_FrameGraphToYaml))
      .def_property_readonly("frames", &FrameGraph::Frames, LC_DOC(core_FrameGraph_Frames))
      .def_property_readonly("robots", &FrameGraph::Robots, LC_DOC(core_FrameGraph_Robots))
      .def("has_frame", &FrameGraph::HasFrame, py::arg("name"), LC_DOC(core_FrameGraph_HasFrame))
      .def("connected", &FrameGraph::Connected, py::arg("a"), py::arg("b"),
           LC_DOC(core_FrameGraph_Connected))
      .def("robots_on_path", &FrameGraph::RobotsOnPath, py::arg("to"), py::arg("from_"),
           LC_DOC(core_FrameGraph_RobotsOnPath))
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
           LC_DOC(core_FrameGraph_RemoveEdge))
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
