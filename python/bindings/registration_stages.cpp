// The registration stages a Python user runs on their own: normals (registration/normals.hpp),
// box crop and voxel-grid subsampling (registration/filters.hpp) and ICP
// (registration/icp.hpp). Normal and ICP options are dicts with the keys of the localize options
// file's `normals:` and `icp:` sections, read by that file's reader.
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include "python/bindings/bindings.hpp"
#include "registration/filters.hpp"
#include "registration/icp.hpp"
#include "registration/kdtree.hpp"
#include "registration/localize_options_io.hpp"
#include "registration/normals.hpp"

namespace lasercell::python {
namespace {

using CloudPtr = std::shared_ptr<PointCloud>;

// The options of one section (`normals`, `icp`) of the options file from a dict.
registration::LocalizeOptions Section(const char* key, const py::object& options) {
  if (options.is_none()) return {};
  py::dict wrapped;
  wrapped[key] = options;
  return SettingsFromDict(wrapped, "options").localize;
}

registration::Viewpoint ViewpointArg(const py::object& viewpoint_mm) {
  if (viewpoint_mm.is_none()) return {};
  return registration::Viewpoint::AtPoint(ToVector3(viewpoint_mm, "viewpoint_mm"));
}

}  // namespace

void BindRegistrationStages(py::module_& m) {
  m.def(
      "estimate_normals",
      [](const PointCloud& cloud, const py::object& viewpoint_mm, const py::object& options,
         int threads) {
        registration::NormalOptions o = Section("normals", options).normals;
        o.viewpoint = ViewpointArg(viewpoint_mm);
        o.threads = threads;
        py::gil_scoped_release release;
        std::size_t dropped = 0;
        return std::make_shared<PointCloud>(registration::WithEstimatedNormals(cloud, o, &dropped));
      },
      py::arg("cloud"), py::arg("viewpoint_mm") = py::none(), py::arg("options") = py::none(),
      py::arg("threads") = 0,
      "A copy of cloud with PCA normals facing viewpoint_mm (default: the origin), grid "
      "neighbours on an organized cloud; points without a fit are dropped. options: the "
      "options file's `normals:` keys, e.g. {'k': 12}.");
  m.def(
      "crop_box",
      [](const PointCloud& cloud, const py::handle& min_mm, const py::handle& max_mm,
         const py::object& frame_from_cloud) {
        BoundingBox box;
        box.min = ToVector3(min_mm, "min_mm");
        box.max = ToVector3(max_mm, "max_mm");
        const Eigen::Isometry3d pose = frame_from_cloud.is_none()
                                           ? Eigen::Isometry3d::Identity()
                                           : ToIsometry(frame_from_cloud, "frame_from_cloud");
        py::gil_scoped_release release;
        return std::make_shared<PointCloud>(registration::CropBox(cloud, box, pose));
      },
      py::arg("cloud"), py::arg("min_mm"), py::arg("max_mm"),
      py::arg("frame_from_cloud") = py::none(),
      "The points inside the box [min_mm, max_mm] (in the frame frame_from_cloud maps to; "
      "default the cloud's own), with all their attributes.");
  m.def(
      "remove_small_clusters",
      [](const PointCloud& cloud, double radius_mm, std::size_t min_cluster_size) {
        registration::ClusterFilterOptions o;
        o.radius_mm = radius_mm;
        o.min_cluster_size = min_cluster_size;
        o.Check();
        py::gil_scoped_release release;
        const registration::ClusterFilterResult r = registration::RemoveSmallClusters(cloud, o);
        py::gil_scoped_acquire gil;
        return py::make_tuple(
            py::array_t<std::int64_t>(static_cast<py::ssize_t>(r.kept.size()),
                                      reinterpret_cast<const std::int64_t*>(r.kept.data())),
            py::array_t<std::int32_t>(static_cast<py::ssize_t>(r.labels.size()), r.labels.data()));
      },
      py::arg("cloud"), py::arg("radius_mm") = 2.0, py::arg("min_cluster_size") = 50,
      "Connected components (points closer than radius_mm; grid neighbours on an organized "
      "cloud): (indices of the points in components of at least min_cluster_size points, "
      "component label per point).");
  m.def(
      "voxel_grid_downsample",
      [](const PointCloud& cloud, double voxel_size_mm, const std::string& normal_mode,
         double normal_split_angle_rad, std::size_t min_points_per_voxel) {
        registration::VoxelGridOptions o;
        o.voxel_size_mm = voxel_size_mm;
        o.normal_mode = registration::ParseVoxelNormalMode(normal_mode, "normal_mode");
        o.normal_split_angle_rad = normal_split_angle_rad;
        o.min_points_per_voxel = min_points_per_voxel;
        o.Check();
        py::gil_scoped_release release;
        return std::make_shared<PointCloud>(registration::VoxelGridDownsample(cloud, o));
      },
      py::arg("cloud"), py::arg("voxel_size_mm"), py::arg("normal_mode") = "average",
      py::arg("normal_split_angle_rad") = 0.0, py::arg("min_points_per_voxel") = 1,
      "One point per occupied voxel at the centroid of its points (Skotheim IV-C); positions "
      "and normals only.");
  m.def(
      "align_icp",
      [](const PointCloud& source, const PointCloud& target, const py::handle& initial,
         const py::object& options) {
        const registration::IcpOptions o = Section("icp", options).icp;
        const Eigen::Isometry3d start = ToIsometry(initial, "initial_target_from_source");
        if (target.normals.empty()) {
          ThrowInput("target: point-to-plane ICP needs target normals (estimate_normals first)");
        }
        py::gil_scoped_release release;
        const registration::KdTree tree(target.positions);
        const registration::IcpResult r =
            registration::AlignIcp(source.positions, tree, target.normals, start, o);
        py::gil_scoped_acquire gil;
        py::dict out;
        out["target_from_source"] = FromIsometry(r.target_from_source);
        out["covariance"] = FromMatrix(r.covariance);
        out["covariance_valid"] = r.covariance_valid;
        out["converged"] = r.converged;
        out["termination"] = registration::ToString(r.termination);
        out["iterations"] = r.iterations;
        out["correspondences"] = r.correspondences;
        out["inliers"] = r.inliers;
        out["rmse_mm"] = r.rmse_mm;
        out["point_rmse_mm"] = r.point_rmse_mm;
        out["summary"] = r.Summary();
        return out;
      },
      py::arg("source"), py::arg("target"), py::arg("initial_target_from_source"),
      py::arg("options") = py::none(),
      "Robust point-to-plane ICP of source onto target (which needs normals) from a 4x4 start. "
      "options: the options file's `icp:` keys. Returns a dict: target_from_source (4x4), "
      "covariance (6x6), converged, iterations, rmse_mm, ...");
}

}  // namespace lasercell::python
