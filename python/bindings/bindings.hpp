#pragma once
// Shared pieces of the Python module `lasercell` (pybind11): NumPy array conversion with the
// argument named in every error, and the registration function of each bound area.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/progress.hpp"
#include "registration/localize_options_io.hpp"

namespace lasercell::python {

namespace py = pybind11;

/// Registers lasercell.Error, InputError (also a ValueError), FileError (also an OSError),
/// OptionError, InternalError and UnitError, and translates the C++ exceptions into them.
void BindErrors(py::module_& m);
/// PointCloud, ReadReport, read/write of PLY and PCD.
void BindPointCloud(py::module_& m);
/// FrameGraph: load/save cell.yaml, transforms with covariance.
void BindFrameGraph(py::module_& m);

/// CameraModel: .cameramodel files, project/unproject arrays.
void BindCameraModel(py::module_& m);
/// PpfModel, localize_in_cloud and its result.
void BindRegistration(py::module_& m);
/// estimate_normals, crop_box, voxel_grid_downsample, align_icp.
void BindRegistrationStages(py::module_& m);
/// Profile files, sweeps (profiles -> points).
void BindTriangulation(py::module_& m);
/// detect_peaks: laser peaks from stripe images.
void BindPeaks(py::module_& m);
/// Board, BoardView, detect_boards, calibrate_intrinsics.
void BindCalibration(py::module_& m);
/// Laser plane calibration (heights, stripes).
void BindLaserPlane(py::module_& m);
/// Half-sphere sensor-to-robot calibration.
void BindSpheres(py::module_& m);
/// Eye-in-hand calibration.
void BindHandEye(py::module_& m);
/// Joint offsets and the laser eye-in-hand from sphere sweeps.
void BindJoints(py::module_& m);
/// scan_line profiles, robot pose files, the laser eye-in-hand from sphere sections.
void BindSections(py::module_& m);
/// TriangleMesh, read_mesh, read_cad_model, Part.
void BindMeshesAndParts(py::module_& m);
/// PartModel, load_part_model, localize_parts, lines_of_sight.
void BindLocalizeParts(py::module_& m);
/// Jobs: load, run, result.
void BindLocalizeJob(py::module_& m);

/// The text of a localize options file from a dict of its keys (JSON, which is YAML flow
/// syntax); NumPy scalars and arrays are accepted. TypeError naming `arg` for a non-dict.
std::string OptionsText(const py::object& options, const std::string& arg);
/// LocalizeSettings from such a dict (None: the defaults), through the options file's reader:
/// OptionError naming `arg` and the field for an unknown key or a wrong type.
registration::LocalizeSettings SettingsFromDict(const py::object& options, const std::string& arg);
/// A ProgressCallback calling `callback(stage, fraction)` with the GIL taken; empty for None.
/// Raising in the callback (or Ctrl-C) stops the work with that exception.
ProgressCallback ToProgress(const py::object& callback);
/// A new 2-D float64 array holding `m`.
py::array_t<double> FromMatrix(const Eigen::MatrixXd& m);
/// A JSON value as the equivalent Python object (dict, list, str, float, bool, None).
py::object JsonToPython(const nlohmann::json& value);

/// Raises lasercell.InputError (a ValueError) with `message`.
[[noreturn]] void ThrowInput(const std::string& message);
/// Raises lasercell.UnitError (an InputError) with `message`.
[[noreturn]] void ThrowUnit(const std::string& message);

/// Copies an (N,3) array of any real dtype and any strides into Vector3d rows, in one pass that
/// also finds the bounding box (into `bounds` when not null and N > 0). Throws TypeError for a
/// non-real dtype, InputError for another shape or (when `finite`) a NaN/inf value; messages
/// name `arg`.
std::vector<Eigen::Vector3d> ToVector3Rows(const py::handle& array, const std::string& arg,
                                           bool finite = true, BoundingBox* bounds = nullptr);
/// An (N,) array of a real or integer dtype, by kind, copied; `expected_size` when not SIZE_MAX.
std::vector<double> ToDoubles(const py::handle& array, const std::string& arg,
                              std::size_t expected_size, bool finite = true);
std::vector<float> ToFloats(const py::handle& array, const std::string& arg,
                            std::size_t expected_size);
std::vector<std::int32_t> ToInt32s(const py::handle& array, const std::string& arg,
                                   std::size_t expected_size);
/// Exactly 3 (or 4) real values, finite, as a vector; InputError naming `arg` otherwise.
Eigen::Vector3d ToVector3(const py::handle& values, const std::string& arg);
Eigen::Vector4d ToVector4(const py::handle& values, const std::string& arg);
/// A 4x4 homogeneous rigid transform -> Isometry3d; InputError unless the last row is
/// [0 0 0 1] and the rotation block is orthonormal within 1e-9.
Eigen::Isometry3d ToIsometry(const py::handle& array, const std::string& arg);
/// Isometry3d -> a new 4x4 float64 array.
py::array_t<double> FromIsometry(const Eigen::Isometry3d& pose);

/// A new (N, D) array holding a copy of N fixed-size Eigen vectors (pixels, points, faces).
template <typename Scalar, int D>
py::array_t<Scalar> RowsArray(const std::vector<Eigen::Matrix<Scalar, D, 1>>& rows) {
  py::array_t<Scalar> out({static_cast<py::ssize_t>(rows.size()), py::ssize_t{D}});
  Scalar* data = out.mutable_data();
  for (const auto& row : rows) data = std::copy(row.data(), row.data() + D, data);
  return out;
}

/// A read-only NumPy view of `rows` x `cols` values at `data` (row-major, contiguous) whose
/// lifetime is tied to `owner` (the Python object that holds the C++ storage).
template <typename T>
py::array ReadOnlyView(const T* data, std::size_t rows, std::size_t cols, py::handle owner) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(rows)};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(cols * sizeof(T))};
  if (cols > 1) {
    shape.push_back(static_cast<py::ssize_t>(cols));
    strides.push_back(static_cast<py::ssize_t>(sizeof(T)));
  }
  py::array view(py::dtype::of<T>(), shape, strides, data, owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

/// A read-only (N, 3) float64 view of `rows` (Vector3d is three packed doubles), kept alive by
/// `owner`; no copy.
inline py::object Vector3View(const std::vector<Eigen::Vector3d>& rows, const py::object& owner) {
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
  return ReadOnlyView(rows.empty() ? nullptr : rows.front().data(), rows.size(), 3, owner);
}

}  // namespace lasercell::python
