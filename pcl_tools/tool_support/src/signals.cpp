#include "occ_improve/tools/signals.hpp"

#include <atomic>
#include <csignal>
#include <ctime>

namespace occ_improve {

namespace {

std::atomic<bool> g_ends_at_once{false};
std::atomic<int> g_soft_signal{0};
std::atomic<long long> g_last_signal_ns{0};  // when the last signal the handlers acted on came (0: none)
static_assert(std::atomic<int>::is_always_lock_free, "the handler's store must be async-signal-safe");
static_assert(std::atomic<long long>::is_always_lock_free, "the handler's store must be async-signal-safe");

// One press, delivered twice: coreutils' timeout sends its signal to the command and again to its process
// group, microseconds apart, and the second one killed the tool at once (no message, its staging folder
// left) as a second Ctrl-C does. A signal this soon after the last is that same press. clock_gettime,
// sigaction, raise and lock-free atomics are async-signal-safe.
constexpr long long kSamePressNs = 50'000'000;

long long now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<long long>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

// Whether this signal repeats the last one acted on; else it becomes the last.
bool repeats_last_signal() {
  const long long now = now_ns(), last = g_last_signal_ns.load();
  if (last != 0 && now - last < kSamePressNs) return true;
  g_last_signal_ns = now;
  return false;
}

void install_handler(void (*handler)(int), int flags);

// A first signal requests the stop; a second (another press) kills at once, the default action.
extern "C" void record_stop_signal(int signal) {
  if (repeats_last_signal()) return;
  if (stop_requested() == 0) {
    request_stop(signal);
    return;
  }
  install_handler(SIG_DFL, 0);
  raise(signal);
}

// The first signal after defer_first_stop_signal: recorded, and the next press cancels.
extern "C" void record_soft_stop_signal(int signal) {
  if (repeats_last_signal()) return;
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
  install_handler(record_stop_signal, 0);  // a second press kills at once; the next run removes what is left
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
