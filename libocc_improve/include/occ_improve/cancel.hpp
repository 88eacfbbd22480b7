#pragma once
// Cancellation: one process-wide stop request that every long loop of the library polls.
//
// A program that wants Ctrl-C to stop a long call (the tools, from their SIGINT/SIGTERM handler) calls
// request_stop(reason); the insertion, the surface and improvement maps, depth prediction, map loading and
// the OctoMap export check it every few thousand columns (a relaxed atomic load, ~1 ns) and throw
// Cancelled. Worker threads see the same flag, and run_parts rethrows after joining them, so a call stops
// within milliseconds whatever its size. A cancelled call leaves its output partial (a grid holds part of
// the frame it was inserting): the caller discards it. The request stays set until clear_stop_request(),
// so every later call stops at once too.
#include "occ_improve/errors.hpp"

#include <cstddef>

namespace occ_improve {

/// Asks running and later library calls to stop. `reason` must be non-zero (the tools pass the signal
/// number). Async-signal-safe: a lock-free atomic store, so a signal handler may call it. The first
/// reason is kept.
void request_stop(int reason) noexcept;

/// The reason of the pending stop request, or 0.
int stop_requested() noexcept;

/// Withdraws the stop request (for a program that carries on after a cancelled call).
void clear_stop_request() noexcept;

/// Throws Cancelled when a stop was requested: the poll of every long loop.
void throw_if_stop_requested();

/// throw_if_stop_requested() on every `every`-th value of a loop counter, for loops whose single step is
/// too short to poll each time (columns, points).
inline void poll_stop(std::size_t counter, std::size_t every = 4096) {
  if (counter % every == 0) throw_if_stop_requested();
}

}  // namespace occ_improve
