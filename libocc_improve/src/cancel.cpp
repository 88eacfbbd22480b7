#include "occ_improve/cancel.hpp"

#include <atomic>

namespace occ_improve {
namespace {
// Lock-free, so storing it from a signal handler is well defined.
std::atomic<int> g_stop_reason{0};
static_assert(std::atomic<int>::is_always_lock_free, "request_stop must be async-signal-safe");
}  // namespace

void request_stop(int reason) noexcept {
  int none = 0;
  g_stop_reason.compare_exchange_strong(none, reason == 0 ? -1 : reason, std::memory_order_relaxed);
}

int stop_requested() noexcept { return g_stop_reason.load(std::memory_order_relaxed); }

void clear_stop_request() noexcept { g_stop_reason.store(0, std::memory_order_relaxed); }

void throw_if_stop_requested() {
  if (const int reason = stop_requested()) throw Cancelled(reason);
}

}  // namespace occ_improve
