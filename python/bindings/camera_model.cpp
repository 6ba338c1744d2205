// lasercell.CameraModel: a calibrated camera (calib/camera_model.hpp), a mrcal lens model with its
// intrinsics and imager size, read from and written to mrcal's .cameramodel files. project and
// unproject take arrays of points or pixels and return arrays; both go through the same mrcal
// calls as lasercell's C++ code, so they agree with mrcal.project / mrcal.unproject.
#include "calib/camera_model.hpp"

#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

using calib::CameraModel;

// (N, d) or (d,) real array -> rows of d doubles; `single` says the input was one vector.
std::vector<double> Rows(const py::handle& array, const std::string& arg, int d, bool* single) {
  const py::array a = py::array::ensure(array);
  if (!a || (a.dtype().kind() != 'f' && a.dtype().kind() != 'i' && a.dtype().kind() != 'u')) {
    throw py::type_error(arg + ": expected a real array of shape (N, " + std::to_string(d) +
                         ") or (" + std::to_string(d) + ",)");
  }
  *single = a.ndim() == 1;
  const bool ok = (a.ndim() == 1 && a.shape(0) == d) || (a.ndim() == 2 && a.shape(1) == d);
  if (!ok) {
    ThrowInput(arg + ": expected shape (N, " + std::to_string(d) + ") or (" + std::to_string(d) +
               ",), got " + std::string(py::str(a.attr("shape"))));
  }
  const std::size_t n = *single ? 1 : static_cast<std::size_t>(a.shape(0));
  return ToDoubles(a.attr("reshape")(py::make_tuple(-1)), arg, n * static_cast<std::size_t>(d));
}

// A new float64 array of shape (n, cols) — or (cols,) when `single` — holding `values`.
py::array_t<double> Out(const std::vector<double>& values, std::size_t n, int cols, bool single) {
  std::vector<py::ssize_t> shape;
  if (!single) shape.push_back(static_cast<py::ssize_t>(n));
  shape.push_back(cols);
  py::array_t<double> out(shape);
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

py::object Project(const CameraModel& camera, const py::handle& points, bool gradients) {
  bool single = false;
  const std::vector<double> p = Rows(points, "points", 3, &single);
  const std::size_t n = p.size() / 3;
  const int k = camera.NumIntrinsics();
  std::vector<double> q(2 * n);
  std::vector<double> dq_dp(gradients ? 6 * n : 0);
  std::vector<double> dq_di(gradients ? 2 * n * static_cast<std::size_t>(k) : 0);
  {
    py::gil_scoped_release release;
    Eigen::Matrix<double, 2, 3> jp;
    Eigen::Matrix<double, 2, Eigen::Dynamic> ji(2, k);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d point(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
      const Eigen::Vector2d pixel =
          gradients ? camera.Project(point, &jp, &ji) : camera.Project(point);
      q[2 * i] = pixel.x();
      q[2 * i + 1] = pixel.y();
      if (!gradients) continue;
      for (int r = 0; r < 2; ++r) {
        for (int c = 0; c < 3; ++c) dq_dp[6 * i + 3 * r + c] = jp(r, c);
        for (int c = 0; c < k; ++c) dq_di[(2 * i + r) * k + c] = ji(r, c);
      }
    }
  }
  py::array_t<double> pixels = Out(q, n, 2, single);
  if (!gradients) return pixels;
  py::array_t<double> jp_out = Out(dq_dp, n, 6, single);
  py::array_t<double> ji_out = Out(dq_di, n, 2 * k, single);
  const std::vector<py::ssize_t> lead =
      single ? std::vector<py::ssize_t>{} : std::vector<py::ssize_t>{static_cast<py::ssize_t>(n)};
  std::vector<py::ssize_t> shape_p = lead, shape_i = lead;
  shape_p.insert(shape_p.end(), {2, 3});
  shape_i.insert(shape_i.end(), {2, k});
  return py::make_tuple(pixels, jp_out.attr("reshape")(shape_p), ji_out.attr("reshape")(shape_i));
}

py::array_t<double> Unproject(const CameraModel& camera, const py::handle& pixels) {
  bool single = false;
  const std::vector<double> q = Rows(pixels, "pixels", 2, &single);
  const std::size_t n = q.size() / 2;
  std::vector<Eigen::Vector2d> in(n);
  for (std::size_t i = 0; i < n; ++i) in[i] = Eigen::Vector2d(q[2 * i], q[2 * i + 1]);
  std::vector<Eigen::Vector3d> rays;
  {
    py::gil_scoped_release release;
    rays = camera.UnprojectMany(in);
  }
  std::vector<double> out(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) out[3 * i + c] = rays[i][c];
  }
  return Out(out, n, 3, single);
}

}  // namespace

void BindCameraModel(py::module_& m) {
  py::class_<CameraModel>(m, "CameraModel", R"doc(
A calibrated camera: a mrcal lens model, its intrinsics (fx fy cx cy, then distortion, in mrcal's
order) and the imager size. Camera frame: +x along columns, +y along rows, +z the optical axis;
the centre of the top-left pixel is (0, 0). Points in mm, pixels in px.)doc")
      .def(py::init([](const std::string& lensmodel, const py::handle& intrinsics, int width,
                       int height) {
             return CameraModel(lensmodel,
                                ToDoubles(intrinsics, "intrinsics", static_cast<std::size_t>(-1)),
                                width, height);
           }),
           py::arg("lensmodel"), py::arg("intrinsics"), py::arg("width"), py::arg("height"),
           "Raises lasercell.InputError for an unknown lens model, a wrong number of intrinsics, "
           "a non-finite value or a non-positive imager size.")
      .def_static("load", &calib::LoadCameraModel, py::arg("path"), LC_DOC(calib_LoadCameraModel))
      .def_static("from_text", &calib::ParseCameraModel, py::arg("text"),
                  py::arg("name") = "camera model", LC_DOC(calib_ParseCameraModel))
      .def(
          "save",
          [](const CameraModel& c, const std::string& path, const std::string& comment) {
            calib::SaveCameraModel(path, c, comment);
          },
          py::arg("path"), py::arg("comment") = "", "Writes a .cameramodel atomically.")
      .def(
          "to_text",
          [](const CameraModel& c, const std::string& comment) {
            return calib::CameraModelText(c, comment);
          },
          py::arg("comment") = "", "The .cameramodel text.")
      .def_property_readonly("lensmodel", &CameraModel::lensmodel,
                             LC_DOC(calib_CameraModel_lensmodel))
      .def_property_readonly(
          "intrinsics",
          [](const CameraModel& c) {
            return py::array_t<double>(static_cast<py::ssize_t>(c.intrinsics().size()),
                                       c.intrinsics().data());
          },
          "(K,) float64 copy: fx fy cx cy, then distortion.")
      .def_property_readonly("width", &CameraModel::width_px, LC_DOC(calib_CameraModel_width_px))
      .def_property_readonly("height", &CameraModel::height_px, LC_DOC(calib_CameraModel_height_px))
      .def_property_readonly(
          "intrinsics_covariance",
          [](const CameraModel& c) -> py::object {
            const Eigen::MatrixXd& cov = c.intrinsics_covariance();
            if (cov.size() == 0) return py::none();
            py::array_t<double> out({cov.rows(), cov.cols()});
            auto view = out.mutable_unchecked<2>();
            for (Eigen::Index r = 0; r < cov.rows(); ++r) {
              for (Eigen::Index c2 = 0; c2 < cov.cols(); ++c2) view(r, c2) = cov(r, c2);
            }
            return out;
          },
          "(K, K) covariance of the intrinsics from the calibration, or None when unknown.")
      .def("project", &Project, py::arg("points"), py::arg("gradients") = false,
           R"doc(Pixels (N, 2) of points (N, 3) in the camera frame, mm (or (2,) of one (3,)).

With gradients=True returns (pixels, dq_dp (N, 2, 3), dq_dintrinsics (N, 2, K)), as
mrcal.project(..., get_gradients=True) does. Points behind a pinhole-like camera give undefined
values, as in mrcal.)doc")
      .def("unproject", &Unproject, py::arg("pixels"),
           "Unit ray directions (N, 3) in the camera frame of pixels (N, 2) (or (3,) of one (2,)).")
      .def("lens_inversion_problem", &calib::LensInversionProblem, py::arg("grid") = 129,
           py::arg("tolerance_px") = 0.01, LC_DOC(calib_LensInversionProblem))
      .def("__repr__", [](const CameraModel& c) {
        return "<lasercell.CameraModel " + c.lensmodel() + " " + std::to_string(c.width_px()) +
               "x" + std::to_string(c.height_px()) + ">";
      });
}

}  // namespace lasercell::python
