// NumPy arrays in: any real dtype and any memory order are accepted and copied into lasercell's
// own storage (which keeps positions finite, core/point_cloud.hpp); a wrong kind of array is a
// TypeError, a wrong shape or a NaN/inf value a lasercell.InputError, each naming the argument.
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

std::string ShapeText(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) {
    if (d > 0) text += ", ";
    text += std::to_string(a.shape(d));
  }
  return text + (a.ndim() == 1 ? ",)" : ")");
}

// The array behind `handle` (lists are converted), with a real or integer dtype.
py::array RealArray(const py::handle& handle, const std::string& arg, bool allow_int) {
  py::array a = py::array::ensure(handle);
  if (!a) throw py::type_error(arg + ": expected a NumPy array (or a nested list of numbers)");
  const char kind = a.dtype().kind();
  const bool ok = kind == 'f' || (allow_int && (kind == 'i' || kind == 'u'));
  if (!ok) {
    throw py::type_error(arg + ": expected " + (allow_int ? "a real or integer" : "a real") +
                         " dtype, got " + std::string(py::str(a.dtype())));
  }
  return a;
}

template <typename T>
py::array_t<T, py::array::c_style | py::array::forcecast> Cast(const py::array& a) {
  return py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
}

void CheckSize(const py::array& a, const std::string& arg, std::size_t expected_size) {
  if (a.ndim() != 1) {
    ThrowInput(arg + ": expected a 1-D array, got shape " + ShapeText(a));
  }
  if (expected_size != std::numeric_limits<std::size_t>::max() &&
      static_cast<std::size_t>(a.shape(0)) != expected_size) {
    ThrowInput(arg + ": expected " + std::to_string(expected_size) +
               " values (one per point), got " + std::to_string(a.shape(0)));
  }
}

void ThrowNotFinite(const std::string& arg, std::size_t index) {
  ThrowInput(arg + ": value at index " + std::to_string(index) +
             " is NaN or infinite; lasercell keeps only finite values (drop that row first)");
}

}  // namespace

std::vector<Eigen::Vector3d> ToVector3Rows(const py::handle& array, const std::string& arg,
                                           bool finite) {
  const py::array a = RealArray(array, arg, true);
  if (a.ndim() != 2 || a.shape(1) != 3) {
    ThrowInput(arg + ": expected shape (N, 3), got " + ShapeText(a));
  }
  const auto values = Cast<double>(a);
  const std::size_t n = static_cast<std::size_t>(a.shape(0));
  std::vector<Eigen::Vector3d> rows(n);
  const double* data = values.data();
  for (std::size_t i = 0; i < n; ++i) {
    rows[i] = Eigen::Vector3d(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
    if (finite && !rows[i].allFinite()) ThrowNotFinite(arg, i);
  }
  return rows;
}

std::vector<double> ToDoubles(const py::handle& array, const std::string& arg,
                              std::size_t expected_size, bool finite) {
  const py::array a = RealArray(array, arg, true);
  CheckSize(a, arg, expected_size);
  const auto values = Cast<double>(a);
  std::vector<double> out(values.data(), values.data() + values.size());
  for (std::size_t i = 0; finite && i < out.size(); ++i) {
    if (!std::isfinite(out[i])) ThrowNotFinite(arg, i);
  }
  return out;
}

std::vector<float> ToFloats(const py::handle& array, const std::string& arg,
                            std::size_t expected_size) {
  const std::vector<double> values = ToDoubles(array, arg, expected_size, true);
  return std::vector<float>(values.begin(), values.end());
}

std::vector<std::int32_t> ToInt32s(const py::handle& array, const std::string& arg,
                                   std::size_t expected_size) {
  const py::array a = py::array::ensure(array);
  if (!a || (a.dtype().kind() != 'i' && a.dtype().kind() != 'u')) {
    throw py::type_error(arg + ": expected an integer dtype" +
                         (a ? ", got " + std::string(py::str(a.dtype())) : std::string()));
  }
  CheckSize(a, arg, expected_size);
  const auto values = Cast<std::int64_t>(a);
  std::vector<std::int32_t> out(values.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::int64_t v = values.data()[i];
    if (v < std::numeric_limits<std::int32_t>::min() ||
        v > std::numeric_limits<std::int32_t>::max()) {
      ThrowInput(arg + ": value " + std::to_string(v) + " at index " + std::to_string(i) +
                 " does not fit a 32-bit index");
    }
    out[i] = static_cast<std::int32_t>(v);
  }
  return out;
}

Eigen::Isometry3d ToIsometry(const py::handle& array, const std::string& arg) {
  const py::array a = RealArray(array, arg, false);
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    ThrowInput(arg + ": expected a 4x4 homogeneous transform, got shape " + ShapeText(a));
  }
  const auto values = Cast<double>(a);
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = values.data()[4 * r + c];
  }
  if (!m.allFinite()) ThrowInput(arg + ": the transform holds NaN or infinite values");
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12) {
    ThrowInput(arg + ": the last row must be [0, 0, 0, 1]");
  }
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const double off = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > 1e-9 || r.determinant() < 0.0) {
    ThrowInput(arg + ": the upper-left 3x3 block is not a rotation (R^T R differs from I by " +
               std::to_string(off) + ", or det R < 0); pass a rigid transform");
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = r;
  pose.translation() = m.topRightCorner<3, 1>();
  return pose;
}

py::array_t<double> FromIsometry(const Eigen::Isometry3d& pose) {
  py::array_t<double> out({4, 4});
  auto view = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) view(r, c) = pose.matrix()(r, c);
  }
  return out;
}

}  // namespace lasercell::python
