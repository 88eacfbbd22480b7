// The fork-join helpers of the insertion (support/parallel.hpp): every task runs once, on any number of
// workers, and a failing task stops the others from taking more and reaches the caller.
#include "../libocc_improve/src/support/parallel.hpp"  // internal: not installed, tested here directly

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace occ_improve::detail {
namespace {

TEST(Parallel, RunInTurnRunsEveryTaskOnceOnAnyNumberOfWorkers) {
  for (const int workers : {1, 2, 3, 8}) {
    for (const int tasks : {0, 1, 2, 7, 64}) {
      std::vector<std::atomic<int>> runs(static_cast<std::size_t>(tasks));
      std::mutex lock;
      std::set<int> workers_seen;
      run_in_turn(workers, tasks, [&](int task, int worker) {
        ++runs[static_cast<std::size_t>(task)];
        const std::lock_guard<std::mutex> guard(lock);
        workers_seen.insert(worker);
      });
      for (int t = 0; t < tasks; ++t) EXPECT_EQ(runs[static_cast<std::size_t>(t)], 1) << workers << " workers, task " << t;
      // Worker indices name the caller's scratch buffers: never more than asked for, nor than the tasks.
      for (const int w : workers_seen) {
        EXPECT_GE(w, 0);
        EXPECT_LT(w, std::max(1, std::min(workers, tasks)));
      }
    }
  }
}

TEST(Parallel, RunInTurnStopsTakingTasksAfterAFailureAndRethrows) {
  std::atomic<int> ran{0};
  EXPECT_THROW(run_in_turn(2, 1000,
                           [&](int task, int) {
                             ++ran;
                             if (task == 3) throw std::runtime_error("task 3");
                             std::this_thread::sleep_for(std::chrono::microseconds(200));
                           }),
               std::runtime_error);
  // The other worker may finish the task it holds (a task takes 0.2 ms, the throw microseconds); none
  // starts the hundreds left.
  EXPECT_GE(ran, 4);
  EXPECT_LT(ran, 100);
}

}  // namespace
}  // namespace occ_improve::detail
