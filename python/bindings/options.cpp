// Options and progress from Python: an options dict becomes the text of lasercell's localize
// options file and is read by that file's one reader (registration/localize_options_io.hpp), so
// the keys, defaults, units and error messages are the file's; a Python callable becomes a
// ProgressCallback that takes the GIL for each call and lets Ctrl-C stop the work.
#include <memory>
#include <string>
#include <string_view>

#include "python/bindings/bindings.hpp"
#include "registration/localize_options_io.hpp"

namespace lasercell::python {

std::string OptionsText(const py::object& options, const std::string& arg) {
  if (options.is_none()) return "{}";
  if (!py::isinstance<py::dict>(options)) {
    throw py::type_error(arg +
                         ": expected a dict of options-file keys, e.g. {'threads': 1, "
                         "'icp': {'max_iterations': 30}}");
  }
  // NumPy scalars and arrays become plain numbers and lists; JSON is YAML flow syntax.
  const py::module_ json = py::module_::import("json");
  const py::object to_plain =
      py::module_::import("builtins")
          .attr("eval")("lambda o: o.tolist() if hasattr(o, 'tolist') else str(o)");
  return json.attr("dumps")(options, py::arg("default") = to_plain).cast<std::string>();
}

registration::LocalizeSettings SettingsFromDict(const py::object& options, const std::string& arg) {
  return registration::ParseLocalizeOptions(OptionsText(options, arg), arg);
}

ProgressCallback ToProgress(const py::object& callback) {
  if (callback.is_none()) return {};
  if (!PyCallable_Check(callback.ptr())) {
    throw py::type_error("progress: expected a callable progress(stage: str, fraction: float)");
  }
  // The library copies and calls the callback without the GIL (the caller released it): the
  // callable is shared by pointer, so copies touch no Python reference count, and the last owner
  // takes the GIL to release it.
  std::shared_ptr<py::object> held(new py::object(callback), [](py::object* o) {
    py::gil_scoped_acquire gil;
    delete o;
  });
  return [held](std::string_view stage, double fraction) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C stops the work
    (*held)(py::str(stage.data(), stage.size()), fraction);
  };
}

py::array_t<double> FromMatrix(const Eigen::MatrixXd& m) {
  py::array_t<double> out({m.rows(), m.cols()});
  auto view = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) view(r, c) = m(r, c);
  }
  return out;
}

py::object JsonToPython(const nlohmann::json& value) {
  return py::module_::import("json").attr("loads")(value.dump());
}

}  // namespace lasercell::python
