#include "occ_improve/tools/signals.hpp"

#include <atomic>
#include <csignal>

namespace occ_improve {

namespace {

std::atomic<bool> g_ends_at_once{false};
std::atomic<int> g_soft_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the handler's store must be async-signal-safe");

extern "C" void record_stop_signal(int signal) { request_stop(signal); }

// The first signal after defer_first_stop_signal: recorded, and the next one cancels (sigaction and a
// lock-free atomic store are async-signal-safe).
extern "C" void record_soft_stop_signal(int signal) {
  g_soft_signal = signal;
  install_stop_signals();
}

void install_handler(void (*handler)(int), int flags) {
  struct sigaction action {};
  action.sa_handler = handler;
  action.sa_flags = flags;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

}  // namespace

void install_stop_signals() {
  install_handler(record_stop_signal, SA_RESETHAND);  // a second Ctrl-C kills at once; the next run removes what is left
}

void defer_first_stop_signal() { install_handler(record_soft_stop_signal, 0); }

int soft_stop_signal() { return g_soft_signal.load(); }

CancelAfter::CancelAfter(int signal, std::chrono::milliseconds timeout) {
  if (signal == 0) return;
  watchdog_ = std::thread([this, signal, timeout] {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!done_.wait_for(lock, timeout, [this] { return finished_; })) request_stop(signal);
  });
}

CancelAfter::~CancelAfter() {
  if (!watchdog_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
  }
  done_.notify_all();
  watchdog_.join();
}

int take_stop_request() {
  const int signal = stop_requested();
  clear_stop_request();
  return signal;
}

void end_process_at_once() { g_ends_at_once = true; }
bool process_ends_at_once() { return g_ends_at_once.load(); }

}  // namespace occ_improve
