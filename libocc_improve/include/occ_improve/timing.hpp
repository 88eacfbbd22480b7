#pragma once
// The one stopwatch of the reports' timings (InsertionReport::seconds, a tool's summary, a progress line's
// rate): the steady clock, so that a change of the system time cannot make a duration negative.
#include <chrono>

namespace occ_improve {

using SteadyClock = std::chrono::steady_clock;

/// Seconds from `start` to now.
inline double seconds_since(SteadyClock::time_point start) {
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

/// Now as seconds since the steady clock's epoch, for code that keeps its times as numbers.
inline double now_seconds() { return std::chrono::duration<double>(SteadyClock::now().time_since_epoch()).count(); }

}  // namespace occ_improve
