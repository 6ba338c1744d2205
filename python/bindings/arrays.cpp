// NumPy arrays in: any real dtype and any memory order are accepted and copied into lasercell's
// own storage (which keeps positions finite, core/point_cloud.hpp); a wrong kind of array is a
// TypeError, a wrong shape or a NaN/inf value a lasercell.InputError, each naming the argument.
#include <sys/mman.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
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

namespace {

// Copies (N, 3) values of type S at any strides into rows, testing finiteness (x - x is 0 for
// finite x, NaN otherwise) and finding the bounding box in the same pass; the failing row is
// searched only when a NaN/inf was seen.
template <typename S>
void FillRows(const py::array& a, std::vector<Eigen::Vector3d>* rows, bool finite,
              const std::string& arg, BoundingBox* bounds) {
  const auto* base = static_cast<const char*>(a.data());
  const py::ssize_t row_stride = a.strides(0), col_stride = a.strides(1);
  const auto at = [&](std::size_t i, int c) {
    return static_cast<double>(*reinterpret_cast<const S*>(
        base + static_cast<py::ssize_t>(i) * row_stride + c * col_stride));
  };
  Eigen::Array3d low = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Array3d high = -low;
  Eigen::Array3d nan_probe = Eigen::Array3d::Zero();
  for (std::size_t i = 0; i < rows->size(); ++i) {
    const Eigen::Array3d p(at(i, 0), at(i, 1), at(i, 2));
    (*rows)[i] = p.matrix();
    nan_probe += p - p;
    low = low.min(p);
    high = high.max(p);
  }
  if (finite && !nan_probe.allFinite()) {
    for (std::size_t i = 0; i < rows->size(); ++i) {
      if (!(*rows)[i].allFinite()) ThrowNotFinite(arg, i);
    }
  }
  if (bounds != nullptr && !rows->empty()) {
    bounds->min = low.matrix();
    bounds->max = high.matrix();
  }
}

// Asks the kernel for transparent huge pages over the 2 MiB-aligned part of a large block not
// yet touched (as NumPy does for its large arrays): a fresh 24 MB block then costs a dozen page
// faults instead of ~6000, which on a VM take longer than the copy itself. Advice only: a kernel
// without THP ignores it.
void AdviseHugePages(void* data, std::size_t bytes) {
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  if (bytes < 2 * kHuge) return;
  const auto begin = (reinterpret_cast<std::uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

}  // namespace

std::vector<Eigen::Vector3d> ToVector3Rows(const py::handle& array, const std::string& arg,
                                           bool finite, BoundingBox* bounds) {
  const py::array a = RealArray(array, arg, true);
  if (a.ndim() != 2 || a.shape(1) != 3) {
    ThrowInput(arg + ": expected shape (N, 3), got " + ShapeText(a));
  }
  std::vector<Eigen::Vector3d> rows(static_cast<std::size_t>(a.shape(0)));  // not yet touched
  AdviseHugePages(rows.data(), rows.size() * sizeof(Eigen::Vector3d));
  // float64 and float32 are read in place at any strides (no temporary array: its fresh pages
  // would cost more than the copy); other dtypes are cast to float64 once first.
  if (py::isinstance<py::array_t<double>>(a)) {
    FillRows<double>(a, &rows, finite, arg, bounds);
  } else if (py::isinstance<py::array_t<float>>(a)) {
    FillRows<float>(a, &rows, finite, arg, bounds);
  } else {
    FillRows<double>(Cast<double>(a), &rows, finite, arg, bounds);
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
  const py::array a = RealArray(array, arg, true);
  CheckSize(a, arg, expected_size);
  const auto values = Cast<float>(a);  // no copy for a float32 array
  std::vector<float> out(values.data(), values.data() + values.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!std::isfinite(out[i])) ThrowNotFinite(arg, i);
  }
  return out;
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

Eigen::Vector3d ToVector3(const py::handle& values, const std::string& arg) {
  const std::vector<double> v = ToDoubles(values, arg, 3);
  return {v[0], v[1], v[2]};
}

Eigen::Vector4d ToVector4(const py::handle& values, const std::string& arg) {
  const std::vector<double> v = ToDoubles(values, arg, 4);
  return {v[0], v[1], v[2], v[3]};
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
