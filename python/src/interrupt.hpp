#pragma once
// Ctrl-C during a long library call. Python's own SIGINT handler only sets a flag that the interpreter
// checks between bytecodes, so a call running with the GIL released (an insertion, an export, a plan)
// ran to its end before KeyboardInterrupt was raised: 5-15 s for a large insert, and an export still
// wrote its file. While such a call runs, SIGINT also asks the library to stop (request_stop, cancel.hpp):
// its loops throw Cancelled within milliseconds. Python's handler still runs (chained), so its flag is set
// and a waiting main thread wakes, and the KeyboardInterrupt comes from Python itself. Only Python's
// default handler is joined this way: a program with its own SIGINT handler (or SIG_IGN, SIG_DFL) keeps it
// as it was, and its calls run to their end.
#include "occ_improve/cancel.hpp"

#include <pybind11/pybind11.h>

namespace occ_improve::python {

namespace py = pybind11;

/// While alive (calls may nest, or run in several threads) and Python's default SIGINT handler is in
/// place, SIGINT also requests a library stop. On destruction the previous handler is back and the stop
/// request withdrawn. Construct and destroy with the GIL held.
class SigintStopsLibrary {
public:
  SigintStopsLibrary();
  ~SigintStopsLibrary();
  SigintStopsLibrary(const SigintStopsLibrary&) = delete;
  SigintStopsLibrary& operator=(const SigintStopsLibrary&) = delete;
  /// Whether a SIGINT came during the call.
  bool interrupted() const;
};

/// Whether the calling thread is Python's main thread (the GIL held).
bool in_main_thread();

/// A call running without the GIL, counted for the interpreter's exit (construct and destroy with the GIL
/// held). A thread that takes the GIL back once Python's finalization began is ended by CPython 3.11 with
/// pthread_exit, whose unwinding cannot leave a C++ destructor (gil_scoped_release's): std::terminate,
/// "terminate called without an active exception". Python does not wait at exit for daemon threads, nor
/// (CPython 3.11) for a thread whose join() a KeyboardInterrupt interrupted: it is marked as stopped. So
/// at exit (an atexit callback, before finalization) calls still running are asked to stop and waited for
/// until they have the GIL back; calls made after that keep the GIL (interpreter_exiting).
class CallWithoutGil {
public:
  CallWithoutGil();
  ~CallWithoutGil();
  CallWithoutGil(const CallWithoutGil&) = delete;
  CallWithoutGil& operator=(const CallWithoutGil&) = delete;
};

/// Whether the interpreter's exit began waiting for the calls (the GIL held): later calls keep the GIL.
bool interpreter_exiting();

/// Registers the wait for running calls with atexit (at import).
void register_exit_wait();

/// f() with the GIL released and SIGINT stopping the library. When Ctrl-C stopped it: in Python's main
/// thread the KeyboardInterrupt of Python's handler; in another thread oi.Cancelled (the main thread gets
/// its KeyboardInterrupt from Python, as for any signal). Take the GIL before calling (f must not touch
/// Python objects).
template <class F>
auto run_interruptible(F&& f) -> decltype(f()) {
  if (interpreter_exiting()) return f();  // the GIL kept: no thread may take it back during finalization
  const CallWithoutGil call;  // first in, last out: counted until the GIL is back and Cancelled handled
  SigintStopsLibrary sigint;
  try {
    py::gil_scoped_release release;
    return f();
  } catch (const Cancelled&) {
    if (!sigint.interrupted() || !in_main_thread()) throw;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Python's handler: KeyboardInterrupt
    throw;
  }
}

}  // namespace occ_improve::python
