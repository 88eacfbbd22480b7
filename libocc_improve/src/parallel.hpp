#pragma once
// A minimal fork-join helper: runs body(part, parts) on `parts` threads (the caller's thread is one of
// them) and rethrows the first exception after all have joined, so no thread outlives the call.
#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace occ_improve::detail {

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
  std::vector<std::thread> threads;
  threads.reserve(static_cast<std::size_t>(parts) - 1);
  for (int p = 1; p < parts; ++p)
    threads.emplace_back([&, p] {
      try {
        body(p, parts);
      } catch (...) {
        errors[static_cast<std::size_t>(p)] = std::current_exception();
      }
    });
  try {
    body(0, parts);
  } catch (...) {
    errors[0] = std::current_exception();
  }
  for (auto& t : threads) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace occ_improve::detail
