#pragma once
// A minimal fork-join helper: runs body(part, parts) on `parts` threads (the caller's thread is one of
// them) and rethrows the first exception after all have joined, so no thread outlives the call.
#include <algorithm>
#include <atomic>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace occ_improve::detail {

/// Boundaries of `parts` blocks of consecutive items (parts + 1 values, the first 0, the last the item
/// count) holding about equal shares of the items' weights; equal numbers of items when they weigh
/// nothing. A block may be empty where one item outweighs a share.
template <typename Weight>
std::vector<int> weighted_blocks(const std::vector<Weight>& weights, int parts) {
  const int items = static_cast<int>(weights.size());
  std::vector<int> begin(static_cast<std::size_t>(parts) + 1);
  for (int part = 0; part <= parts; ++part)
    begin[static_cast<std::size_t>(part)] = static_cast<int>(static_cast<long long>(items) * part / parts);
  Weight total = 0;
  for (const Weight w : weights) total += w;
  if (!(total > 0)) return begin;
  Weight before = 0;
  for (int item = 0, part = 1; item < items && part < parts; ++item) {
    before += weights[static_cast<std::size_t>(item)];
    while (part < parts && before * parts >= total * part) begin[static_cast<std::size_t>(part++)] = item + 1;
  }
  return begin;
}

inline int resolve_thread_count(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

template <typename Body>
void run_parts(int parts, Body&& body) {
  if (parts <= 1) {
    body(0, 1);
    return;
  }
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(parts));
  const auto run = [&](int p) {
    try {
      body(p, parts);
    } catch (...) {
      errors[static_cast<std::size_t>(p)] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(static_cast<std::size_t>(parts) - 1);
  // A thread the system refuses (std::system_error) must not escape with others still joinable, which
  // would std::terminate: the caller runs the parts left over itself, so every part runs exactly once.
  int started = 1;
  try {
    for (; started < parts; ++started) threads.emplace_back(run, started);
  } catch (const std::system_error&) {
  }
  run(0);
  for (int p = started; p < parts; ++p) run(p);
  for (auto& t : threads) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

/// Runs body(task, worker) for every task in [0, tasks) on up to `workers` threads (run_parts): each
/// worker takes the next task nobody has taken, in ascending order, so a worker whose tasks were quick
/// takes more and an uneven split does not leave a thread idle. Once a body throws, no worker takes
/// another task; run_parts rethrows.
template <typename Body>
void run_in_turn(int workers, int tasks, Body&& body) {
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  run_parts(std::max(1, std::min(workers, tasks)), [&](int worker, int) {
    for (int task = next++; task < tasks && !failed; task = next++) {
      try {
        body(task, worker);
      } catch (...) {
        failed = true;
        throw;
      }
    }
  });
}

}  // namespace occ_improve::detail
