// The library's error hierarchy as Python exceptions with the same messages. Each also derives from the
// built-in exception a Python caller would catch for that kind of failure (ValueError for bad values,
// OSError for files that cannot be read or written), so generic handlers work too.
#include "bindings.hpp"

#include "occ_improve/errors.hpp"

#include <cstring>

namespace occ_improve::python {
namespace {

// Returns a handle that owns one reference on purpose: the translator uses it until the interpreter
// exits, and a static py::object would be released after Python is finalised.
py::handle new_exception(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string qualified = std::string("occ_improve.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  m.attr(name) = py::handle(type);
  return py::handle(type);
}

// Raises `type` with `message`, whose bytes may not be UTF-8 (a path the file system named in other bytes:
// PyErr_SetString failed to decode it and the exception came without a message): such bytes read "\xff".
void raise_with_message(py::handle type, const char* message) {
  PyObject* text = PyUnicode_DecodeUTF8(message, static_cast<Py_ssize_t>(std::strlen(message)), "backslashreplace");
  if (!text) return;  // the decoding's own error (memory) is set
  PyErr_SetObject(type.ptr(), text);
  Py_DECREF(text);
}

}  // namespace

void bind_errors(py::module_& m) {
  const py::object builtins = py::module_::import("builtins");
  // Static: the translator below runs long after this function returns.
  static py::handle error, invalid_parameter, invalid_input, io_error, format_error, resource_limit, cancelled;
  error = new_exception(m, "Error", py::make_tuple(builtins.attr("RuntimeError")),
                        "Root of every exception raised by occ_improve.");
  invalid_parameter = new_exception(m, "InvalidParameter", py::make_tuple(error, builtins.attr("ValueError")),
                                    "A parameter is out of its accepted range (the message names it and the range).");
  invalid_input = new_exception(m, "InvalidInput", py::make_tuple(error, builtins.attr("ValueError")),
                                "Input data cannot be used as a whole (empty, wrong shape, wrong size).");
  io_error = new_exception(m, "IoError", py::make_tuple(error, builtins.attr("OSError")),
                           "A file cannot be opened, read or written.");
  format_error = new_exception(m, "FormatError", py::make_tuple(error, builtins.attr("ValueError")),
                               "A file was read but is not in the expected format (corrupt, truncated, other version).");
  resource_limit = new_exception(m, "ResourceLimit", py::make_tuple(error),
                                 "A request would exceed a configured resource limit (e.g. the grid memory cap).");
  cancelled = new_exception(m, "Cancelled", py::make_tuple(error),
                            "A call stopped by a stop request (a Ctrl-C during a call is raised as KeyboardInterrupt).");
  // Most derived first: the C++ types form a hierarchy and the first matching catch wins.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidParameter& e) {
      raise_with_message(invalid_parameter, e.what());
    } catch (const InvalidInput& e) {
      raise_with_message(invalid_input, e.what());
    } catch (const IoError& e) {
      raise_with_message(io_error, e.what());
    } catch (const FormatError& e) {
      raise_with_message(format_error, e.what());
    } catch (const ResourceLimit& e) {
      raise_with_message(resource_limit, e.what());
    } catch (const Cancelled& e) {
      raise_with_message(cancelled, e.what());
    } catch (const Error& e) {
      raise_with_message(error, e.what());
    }
  });
}

}  // namespace occ_improve::python
