#pragma once
// Fork-join helpers over one pool of worker threads kept for the process: run_parts(parts, body) runs
// body(part, parts) for every part, the caller's thread taking parts too, and rethrows the first exception
// once every part has finished, so no part outlives the call.
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
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

/// The worker threads every run_parts shares, started as calls first need them and kept until the
/// process ends (a frame calls run_parts 4-5 times; a thread's start and join cost 40-50 us each time, a
/// few percent of a closed-loop round). A part no worker has taken is run by the caller, so a call
/// completes whatever the pool's size: with fewer workers than parts (the pool keeps at most one per
/// core beside the caller), when the system refuses a thread, or when run_parts is called from a part.
class WorkerPool {
public:
  /// The process's pool, kept until the process ends (a fresh one in a child after fork(), whose workers
  /// are not copied).
  static WorkerPool& shared();
  WorkerPool() = default;
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  ~WorkerPool();  ///< lets the workers finish and joins them (a pool of one's own; shared() is never destroyed)

  /// task(part) for every part in [0, parts), on the calling thread and up to parts - 1 workers; returns
  /// once all have returned. `task` must not throw.
  void run(int parts, const std::function<void(int)>& task);
  std::size_t worker_count() const;

private:
  struct Batch {
    const std::function<void(int)>* task;
    int parts;
    std::atomic<int> next{0};  // the next part to take
    int finished = 0;          // guarded by mutex_
  };
  void add_workers(std::size_t wanted);  // with mutex_ held
  void work();                           // a worker's loop
  void finish(Batch& batch);

  mutable std::mutex mutex_;
  std::condition_variable posted_, finished_;
  std::deque<Batch*> open_;  // batches with parts not yet taken, oldest first
  std::vector<std::thread> workers_;
  bool stopping_ = false;
  bool refused_ = false;  // the system refused a thread: no more are asked for
};

template <typename Body>
void run_parts(int parts, Body&& body) {
  if (parts <= 1) {
    body(0, 1);
    return;
  }
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(parts));
  const std::function<void(int)> task = [&](int p) {
    try {
      body(p, parts);
    } catch (...) {
      errors[static_cast<std::size_t>(p)] = std::current_exception();
    }
  };
  WorkerPool::shared().run(parts, task);
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
