#pragma once
// Shared pieces of the Python module: one bind_* function per library header group, the Mapper holder
// that serialises calls from several Python threads, and small helpers for struct bindings.
#include "interrupt.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"

#include <pybind11/pybind11.h>

#include <initializer_list>
#include <limits>
#include <mutex>
#include <string>
#include <type_traits>
#include <utility>

namespace occ_improve::python {

namespace py = pybind11;

void bind_errors(py::module_& m);
void bind_presets(py::module_& m);
void bind_mapper(py::module_& m);
void bind_analysis(py::module_& m);
void bind_planner(py::module_& m);
void bind_io(py::module_& m);
void bind_internals(py::module_& m);
void bind_prediction(py::module_& m);

/// The Python `Mapper`: the C++ Mapper plus a mutex. Calls release the GIL (so a grabber thread keeps
/// running) and then take the mutex, so two Python threads never modify one Mapper at the same time.
struct PyMapper {
  explicit PyMapper(Mapper m) : mapper(std::move(m)) {}
  Mapper mapper;
  std::mutex mutex;
};

/// Runs f(mapper) with the GIL released and the Mapper's mutex held, Ctrl-C stopping it
/// (run_interruptible: KeyboardInterrupt; an interrupted insertion leaves part of its frame in the map).
/// The lock is taken after the GIL release, so it is given back before the GIL is retaken: a thread that
/// holds the GIL and waits for the mutex can never block the thread that holds the mutex. f must not
/// touch Python objects.
template <class F>
auto with_mapper(PyMapper& m, F&& f) {
  return run_interruptible([&] {
    std::lock_guard<std::mutex> lock(m.mutex);
    return f(m.mapper);
  });
}

/// A constructor from keyword arguments only, each naming a field: T(fx=500.0, width=320). An unknown
/// name is a TypeError, as for a Python function; values are checked by the field's own type.
template <class T, class Class>
void def_keyword_init(Class& cls) {
  cls.def(py::init([](const py::kwargs& kwargs) {
            py::object self = py::cast(T{});
            for (const auto& item : kwargs) {
              const std::string name = py::str(item.first);
              if (!py::hasattr(self, item.first))
                throw py::type_error(std::string(py::str(py::type::of(self).attr("__name__"))) +
                                     "() got an unexpected keyword argument '" + name + "'");
              py::setattr(self, item.first, item.second);
            }
            return self.cast<T>();
          }),
          "Defaults for every field; keyword arguments set fields by name.");
}

/// A Python int (or anything with __index__, as numpy's integers) as integer type T, for the field named
/// `field`: out of T's range is InvalidParameter naming the field, the value and the range, where
/// pybind11's own conversion raises a TypeError that only lists the setter's signature.
template <class T>
T int_for_field(const py::object& value, const std::string& field) {
  if (py::isinstance<py::bool_>(value) || !PyIndex_Check(value.ptr()))
    throw py::type_error(field + " takes an int, not " + std::string(py::repr(value)));
  const py::int_ number = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  const py::int_ lowest(std::numeric_limits<T>::lowest()), highest(std::numeric_limits<T>::max());
  if (number < lowest || number > highest)
    throw InvalidParameter(field + " = " + std::string(py::repr(number)) + " is out of range [" +
                           std::string(py::repr(lowest)) + ", " + std::string(py::repr(highest)) + "]");
  return number.cast<T>();
}

/// Getter and setter of an integer field for def_property, the setter through int_for_field.
template <class C, class T>
auto int_field_getter(T C::*member) {
  return [member](const C& object) { return object.*member; };
}
template <class C, class T>
auto int_field_setter(T C::*member, std::string name) {
  static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>, "for integer fields");
  return [member, name](C& object, const py::object& value) {
    const std::string class_name = py::str(py::type::of<C>().attr("__name__"));
    object.*member = int_for_field<T>(value, class_name + "." + name);
  };
}

/// __repr__ as Name(field=value, ...) over the listed fields.
template <class Class>
void def_fields_repr(Class& cls, std::initializer_list<const char*> fields) {
  std::vector<std::string> names(fields.begin(), fields.end());
  cls.def("__repr__", [names](const py::object& self) {
    std::string out = std::string(py::str(py::type::of(self).attr("__name__"))) + "(";
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (i) out += ", ";
      out += names[i] + "=" + std::string(py::repr(self.attr(names[i].c_str())));
    }
    return out + ")";
  });
}

}  // namespace occ_improve::python
