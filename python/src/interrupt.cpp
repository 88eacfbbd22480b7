#include "interrupt.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <mutex>
#include <thread>

#include <pthread.h>
#include <pythread.h>

namespace occ_improve::python {
namespace {

std::mutex installing;               // guards the fields below but `fired`
int active = 0;                      // SigintStopsLibrary objects alive
bool installed = false;              // SIGINT runs stop_library, then Python's handler
struct sigaction previous {};        // Python's handler, chained and restored
std::atomic<bool> fired{false};      // a SIGINT came while installed

extern "C" void stop_library(int signal, siginfo_t* info, void* context) {
  fired.store(true);  // async-signal-safe: lock-free atomic stores, then Python's own (async-signal-safe) handler
  request_stop(SIGINT);
  if (previous.sa_flags & SA_SIGINFO)
    previous.sa_sigaction(signal, info, context);
  else if (previous.sa_handler != SIG_IGN && previous.sa_handler != SIG_DFL)
    previous.sa_handler(signal);
}

// Whether SIGINT's Python-level handler is Python's default (KeyboardInterrupt), the GIL held. Asked on
// every GIL-free call (every Mapper method): the functions are looked up once, and kept until the process
// ends (released handles: a static py::object would be freed after the interpreter).
bool python_default_handler() {
  static const py::handle getsignal = py::object(py::module_::import("signal").attr("getsignal")).release();
  static const py::handle default_handler = py::object(py::module_::import("signal").attr("default_int_handler")).release();
  return getsignal(static_cast<int>(SIGINT)).is(default_handler);
}

int calls_without_gil = 0;  // CallWithoutGil objects alive; guarded by the GIL
bool exiting = false;       // the exit wait began: later calls keep the GIL; guarded by the GIL

// A forked child holds none of its parent's threads, so none of their calls.
extern "C" void forget_calls_in_child() { calls_without_gil = 0; }

// atexit: the GIL held, finalization not begun (non-daemon threads were joined before). Calls still
// running (daemon threads, a thread whose interrupted join() marked it stopped) are asked to stop and
// waited for until each has the GIL back; they then end as Python code, which finalization handles.
// A call that polls no stop (blocked in the system) is not waited for past this, nor after a further
// Ctrl-C: the exit must not hang for good (it then risks the abort this wait avoids, as before it).
constexpr auto kLongestExitWait = std::chrono::seconds(10);

void wait_for_calls_at_exit() {
  exiting = true;
  if (calls_without_gil == 0) return;
  request_stop(-1);  // "cancelled (stop requested, reason -1)"; a pending SIGINT's reason is kept
  const auto give_up = std::chrono::steady_clock::now() + kLongestExitWait;
  while (calls_without_gil > 0 && std::chrono::steady_clock::now() < give_up) {
    {
      py::gil_scoped_release release;  // the calls take the GIL to end
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (PyErr_CheckSignals() != 0) {  // Ctrl-C again: stop waiting
      PyErr_Clear();
      break;
    }
  }
  clear_stop_request();  // calls in atexit callbacks that run after this one (keeping the GIL) run to their end
}

}  // namespace

CallWithoutGil::CallWithoutGil() { ++calls_without_gil; }
CallWithoutGil::~CallWithoutGil() { --calls_without_gil; }

bool interpreter_exiting() { return exiting; }

void register_exit_wait() {
  pthread_atfork(nullptr, nullptr, &forget_calls_in_child);
  py::module_::import("atexit").attr("register")(py::cpp_function(&wait_for_calls_at_exit));
}

SigintStopsLibrary::SigintStopsLibrary() {
  const bool join = python_default_handler();
  const std::lock_guard<std::mutex> lock(installing);
  if (active++ > 0 || !join) return;
  struct sigaction current {};
  sigaction(SIGINT, nullptr, &current);
  previous = current;
  struct sigaction ours {};
  ours.sa_sigaction = &stop_library;
  ours.sa_flags = SA_SIGINFO;
  sigemptyset(&ours.sa_mask);
  installed = sigaction(SIGINT, &ours, nullptr) == 0;
}

SigintStopsLibrary::~SigintStopsLibrary() {
  const std::lock_guard<std::mutex> lock(installing);
  if (--active > 0) return;
  if (installed) sigaction(SIGINT, &previous, nullptr);
  installed = false;
  if (fired.exchange(false)) clear_stop_request();
}

bool SigintStopsLibrary::interrupted() const { return fired.load(); }

bool in_main_thread() {
  const py::object main = py::module_::import("threading").attr("main_thread")();
  return main.attr("ident").cast<unsigned long>() == PyThread_get_thread_ident();
}

}  // namespace occ_improve::python
