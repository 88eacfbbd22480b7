#include "occ_improve/tools/signals.hpp"

#include <atomic>
#include <csignal>

namespace occ_improve {

namespace {

std::atomic<bool> g_ends_at_once{false};

extern "C" void record_stop_signal(int signal) { request_stop(signal); }

}  // namespace

void install_stop_signals() {
  struct sigaction action {};
  action.sa_handler = record_stop_signal;
  action.sa_flags = SA_RESETHAND;  // a second Ctrl-C kills at once; the next run removes what is left
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int take_stop_request() {
  const int signal = stop_requested();
  clear_stop_request();
  return signal;
}

void end_process_at_once() { g_ends_at_once = true; }
bool process_ends_at_once() { return g_ends_at_once.load(); }

}  // namespace occ_improve
