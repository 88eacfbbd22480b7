#pragma once
// Shared pieces of the Python module: one bind_* function per library header group, the Mapper holder
// that serialises calls from several Python threads, and the helpers of struct bindings (keyword
// constructor, copy, pickle, repr).
#include "interrupt.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"

#include <Eigen/Geometry>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <initializer_list>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

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
  explicit PyMapper(Mapper m, std::optional<Eigen::Isometry3d> pose = std::nullopt)
      : mapper(std::move(m)), world_from_sensor(std::move(pose)) {}
  Mapper mapper;
  std::mutex mutex;
  /// Where the map's sensor frame lies in the world: save() writes it, load_map() reads it back.
  std::optional<Eigen::Isometry3d> world_from_sensor;
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

/// The name of a bound class, for messages: "PlanRequest".
inline std::string class_name(const py::handle& type) { return py::str(type.attr("__name__")); }

/// The fields of a struct class: its read-write properties (def_readwrite, def_property with a setter), in
/// the order they were bound. The keyword constructor, pickle and __repr__ all go through this one list, so
/// a field bound once is in all three.
inline std::vector<std::string> struct_fields(const py::handle& type) {
  std::vector<std::string> names;
  for (const auto& item : py::dict(type.attr("__dict__")))
    if (PyObject_TypeCheck(item.second.ptr(), &PyProperty_Type) && !item.second.attr("fset").is_none())
      names.push_back(py::str(item.first));
  return names;
}

/// The fields' values by name: what pickle stores and struct_from_fields takes back.
inline py::dict fields_of(const py::object& self) {
  py::dict values;
  for (const std::string& name : struct_fields(py::type::of(self))) values[name.c_str()] = self.attr(name.c_str());
  return values;
}

/// A T with the given fields set by name, each through its own setter (so checked as an assignment is);
/// the others keep T's defaults. A name that is no field is a TypeError, as for a Python function.
template <class T>
T struct_from_fields(const py::dict& values) {
  py::object self = py::cast(T{});
  const py::handle type = py::type::of(self);
  const std::vector<std::string> fields = struct_fields(type);
  for (const auto& item : values) {
    const std::string name = py::str(item.first);
    if (std::find(fields.begin(), fields.end(), name) == fields.end())
      throw py::type_error(class_name(type) + "() got an unexpected keyword argument '" + name + "'");
    py::setattr(self, item.first, item.second);
  }
  return self.cast<T>();
}

/// __copy__ and __deepcopy__ as a C++ copy: the structs hold values only (nested structs, vectors,
/// optionals), so the copy shares nothing with the original.
template <class T, class Class>
void def_copy(Class& cls) {
  cls.def("__copy__", [](const T& self) { return T(self); })
      .def("__deepcopy__", [](const T& self, const py::dict&) { return T(self); }, py::arg("memo"));
}

/// Name(field=value, ...) over the named fields.
inline std::string fields_repr(const py::object& self, const std::vector<std::string>& names) {
  std::string out = class_name(py::type::of(self)) + "(";
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i) out += ", ";
    out += names[i] + "=" + std::string(py::repr(self.attr(names[i].c_str())));
  }
  return out + ")";
}

/// __repr__ over the listed fields, for the read-only results (their fields have no setter, so
/// struct_fields does not see them; per-ray arrays are left out: a repr is one line).
template <class Class>
void def_fields_repr(Class& cls, std::initializer_list<const char*> fields) {
  std::vector<std::string> names(fields.begin(), fields.end());
  cls.def("__repr__", [names](const py::object& self) { return fields_repr(self, names); });
}

/// A parameter struct's Python side, all from its fields (struct_fields, read when called, so the fields
/// may be bound after this): a constructor from keyword arguments only, each naming a field
/// (T(fx=500.0, width=320)); copy and deepcopy; pickle as {field: value} (nested structs and enums
/// pickle themselves); __repr__ listing every field.
template <class T, class Class>
void def_value_struct(Class& cls) {
  cls.def(py::init([](const py::kwargs& kwargs) { return struct_from_fields<T>(kwargs); }),
          "Defaults for every field; keyword arguments set fields by name.");
  def_copy<T>(cls);
  cls.def(py::pickle([](const py::object& self) { return fields_of(self); },
                     [](const py::dict& state) { return struct_from_fields<T>(state); }));
  cls.def("__repr__", [](const py::object& self) { return fields_repr(self, struct_fields(py::type::of(self))); });
  // Equal when every field is (arrays by value), as dataclasses compare: PinholeIntrinsics() ==
  // PinholeIntrinsics() was False. Mutable, so unhashable, as a dataclass with eq (pybind11 drops __hash__).
  cls.def("__eq__", [](const py::object& self, const py::object& other) -> py::object {
    if (!py::type::of(other).is(py::type::of(self))) return py::reinterpret_borrow<py::object>(Py_NotImplemented);
    const py::dict mine = fields_of(self), theirs = fields_of(other);
    const py::object array_equal = py::module_::import("numpy").attr("array_equal");
    for (const auto& [name, value] : mine) {
      const py::object a = py::reinterpret_borrow<py::object>(value), b = theirs[name];
      const bool arrays = py::isinstance<py::array>(a) || py::isinstance<py::array>(b);
      if (!(arrays ? array_equal(a, b).cast<bool>() : a.equal(b))) return py::bool_(false);
    }
    return py::bool_(true);
  });
}

/// A member's value from its pickled state; specialised where pybind11's own caster does not suit.
template <class M>
M from_state(const py::handle& value) {
  return value.cast<M>();
}

/// copy and pickle of a plain aggregate without setters (a result such as Region) through the listed
/// members: the state is their values in this order.
template <class T, class Class, class... M>
void def_members_pickle(Class& cls, M T::*... members) {
  def_copy<T>(cls);
  cls.def(py::pickle([members...](const T& x) { return py::make_tuple(x.*members...); },
                     [members...](const py::tuple& state) {
                       if (state.size() != sizeof...(M))
                         throw InvalidInput("a pickled " + class_name(py::type::of<T>()) + " holds " +
                                            std::to_string(state.size()) + " values, not " +
                                            std::to_string(sizeof...(M)));
                       T x{};
                       std::size_t i = 0;
                       ((x.*members = from_state<M>(state[i++])), ...);  // left to right: the comma's order
                       return x;
                     }));
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
    object.*member = int_for_field<T>(value, class_name(py::type::of<C>()) + "." + name);
  };
}

}  // namespace occ_improve::python
