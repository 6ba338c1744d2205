// lasercell's three error tiers (core/error.hpp) as Python exceptions:
//   Error(RuntimeError)
//   ├─ InputError(Error, ValueError)        invalid input or options: what to fix is in the text
//   │  ├─ FileError(InputError, OSError)    .path names the file
//   │  ├─ OptionError(InputError)           an options field out of range
//   │  └─ UnitError(InputError)             an array's extent suggests metres, not millimetres
//   └─ InternalError(Error)                 a bug in lasercell
// The messages are the C++ messages, unchanged.
#include <string>

#include "core/error.hpp"
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

// Exception classes live as long as the interpreter's module; the handles are never released,
// since the translator may run until the interpreter shuts down.
struct ExceptionTypes {
  py::handle error, input, file, option, unit, internal;
};
ExceptionTypes& Types() {
  static ExceptionTypes types;
  return types;
}

py::handle NewException(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string qualified = std::string("lasercell.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.attr(name) = py::handle(type);
  return py::handle(type);
}

}  // namespace

void ThrowInput(const std::string& message) {
  PyErr_SetString(Types().input.ptr(), message.c_str());
  throw py::error_already_set();
}

void BindErrors(py::module_& m) {
  ExceptionTypes& t = Types();
  const py::handle builtins_value_error(PyExc_ValueError);
  const py::handle builtins_os_error(PyExc_OSError);
  t.error = NewException(m, "Error", py::make_tuple(py::handle(PyExc_RuntimeError)),
                         "Base of every exception lasercell raises.");
  t.input = NewException(m, "InputError", py::make_tuple(t.error, builtins_value_error),
                         "Invalid input data or options; the message says what to fix.");
  t.file = NewException(m, "FileError", py::make_tuple(t.input, builtins_os_error),
                        "A file that cannot be read, parsed or written; .path names it.");
  t.option = NewException(m, "OptionError", py::make_tuple(t.input),
                          "An options field out of range; the message names the field.");
  t.unit = NewException(m, "UnitError", py::make_tuple(t.input),
                        "An array's extent suggests metres; lasercell works in millimetres.");
  t.internal = NewException(m, "InternalError", py::make_tuple(t.error),
                            "A broken internal invariant: a bug in lasercell.");
  py::register_exception_translator([](std::exception_ptr p) {
    const ExceptionTypes& types = Types();
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FileError& e) {
      // OSError's constructor takes (errno, strerror, filename); set the message and .path.
      py::object exception =
          py::reinterpret_steal<py::object>(PyObject_CallFunction(types.file.ptr(), "s", e.what()));
      if (!exception) throw py::error_already_set();
      exception.attr("path") = e.path();
      PyErr_SetObject(types.file.ptr(), exception.ptr());
    } catch (const OptionError& e) {
      PyErr_SetString(types.option.ptr(), e.what());
    } catch (const InputError& e) {
      PyErr_SetString(types.input.ptr(), e.what());
    } catch (const InternalError& e) {
      PyErr_SetString(types.internal.ptr(), e.what());
    } catch (const Error& e) {
      PyErr_SetString(types.error.ptr(), e.what());
    }
  });
}

void ThrowUnit(const std::string& message) {
  PyErr_SetString(Types().unit.ptr(), message.c_str());
  throw py::error_already_set();
}

}  // namespace lasercell::python
