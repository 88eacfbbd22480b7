#pragma once
// Ctrl-C during a long library call. Python's own SIGINT handler only sets a flag that the interpreter
// checks between bytecodes, so a call running with the GIL released (an insertion, an export, a plan)
// ran to its end before KeyboardInterrupt was raised: 5-15 s for a large insert, and an export still
// wrote its file. While such a call runs, SIGINT instead asks the library to stop (request_stop,
// cancel.hpp): its loops throw Cancelled within milliseconds, which the caller gets as KeyboardInterrupt,
// as from any Python code. A program that ignores SIGINT, or leaves the system default, keeps its choice.
#include "occ_improve/cancel.hpp"

#include <pybind11/pybind11.h>

namespace occ_improve::python {

namespace py = pybind11;

/// While alive (calls may nest, or run in several threads), SIGINT requests a library stop. On
/// destruction the previous handler is back and the stop request withdrawn; a SIGINT that came while
/// the call still completed, or that stopped a call outside the main thread, is passed on to Python
/// (PyErr_SetInterrupt), unless mark_delivered() said it was raised as KeyboardInterrupt already.
class SigintStopsLibrary {
public:
  SigintStopsLibrary();
  ~SigintStopsLibrary();
  SigintStopsLibrary(const SigintStopsLibrary&) = delete;
  SigintStopsLibrary& operator=(const SigintStopsLibrary&) = delete;
  /// Whether a SIGINT came during the call.
  bool interrupted() const;
  /// Says the SIGINT was raised as KeyboardInterrupt, so that it is not passed on again.
  void mark_delivered();
};

/// Whether the calling thread is Python's main thread (the GIL held).
bool in_main_thread();

/// f() with the GIL released and SIGINT stopping the library. When Ctrl-C stopped it: KeyboardInterrupt
/// in Python's main thread, as Python raises it; in another thread oi.Cancelled, and the main thread gets
/// its KeyboardInterrupt. Take the GIL before calling (f must not touch Python objects).
template <class F>
auto run_interruptible(F&& f) -> decltype(f()) {
  SigintStopsLibrary sigint;
  try {
    py::gil_scoped_release release;
    return f();
  } catch (const Cancelled&) {
    if (!sigint.interrupted() || !in_main_thread()) throw;
  }
  sigint.mark_delivered();
  PyErr_SetNone(PyExc_KeyboardInterrupt);
  throw py::error_already_set();
}

}  // namespace occ_improve::python
