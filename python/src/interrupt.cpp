#include "interrupt.hpp"

#include <atomic>
#include <csignal>
#include <mutex>

#include <pythread.h>

namespace occ_improve::python {
namespace {

std::mutex installing;                 // guards the fields below but the two atomics
int active = 0;                        // SigintStopsLibrary objects alive
bool installed = false;                // SIGINT is ours (Python's handler was there to take over)
struct sigaction previous {};
std::atomic<bool> fired{false};        // a SIGINT came while ours
std::atomic<bool> delivered{false};    // ... and was raised as KeyboardInterrupt

extern "C" void stop_library(int) {  // async-signal-safe: two lock-free atomic stores
  fired.store(true);
  request_stop(SIGINT);
}

}  // namespace

SigintStopsLibrary::SigintStopsLibrary() {
  const std::lock_guard<std::mutex> lock(installing);
  if (active++ > 0) return;
  struct sigaction current {};
  sigaction(SIGINT, nullptr, &current);
  const bool handled = (current.sa_flags & SA_SIGINFO) || (current.sa_handler != SIG_IGN && current.sa_handler != SIG_DFL);
  installed = handled;
  if (!installed) return;
  previous = current;
  struct sigaction ours {};
  ours.sa_handler = &stop_library;
  sigemptyset(&ours.sa_mask);
  sigaction(SIGINT, &ours, nullptr);
}

SigintStopsLibrary::~SigintStopsLibrary() {
  const std::lock_guard<std::mutex> lock(installing);
  if (--active > 0) return;
  if (installed) sigaction(SIGINT, &previous, nullptr);
  installed = false;
  if (!fired.exchange(false)) return;
  clear_stop_request();
  if (!delivered.exchange(false)) PyErr_SetInterrupt();  // Python raises KeyboardInterrupt at its next check
}

bool SigintStopsLibrary::interrupted() const { return fired.load(); }

void SigintStopsLibrary::mark_delivered() { delivered.store(true); }

bool in_main_thread() {
  const py::object main = py::module_::import("threading").attr("main_thread")();
  return main.attr("ident").cast<unsigned long>() == PyThread_get_thread_ident();
}

}  // namespace occ_improve::python
