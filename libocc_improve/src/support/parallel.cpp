#include "support/parallel.hpp"

#include <algorithm>
#include <system_error>

#include <unistd.h>

namespace occ_improve::detail {

WorkerPool& WorkerPool::shared() {
  // Never destroyed: at exit another thread (a Python thread with the GIL released) may still be in run(),
  // or a part may call exit(); the workers wait idle and end with the process. A forked child holds none
  // of the parent's workers (and maybe a mutex some worker held): it takes a pool of its own and never
  // touches the parent's copy.
  static std::mutex guard;
  static pid_t owner = 0;
  static WorkerPool* pool = nullptr;
  const std::lock_guard<std::mutex> lock(guard);
  if (!pool || owner != ::getpid()) {
    pool = new WorkerPool();  // NOLINT(cppcoreguidelines-owning-memory): kept for the process, see above
    owner = ::getpid();
  }
  return *pool;
}

WorkerPool::~WorkerPool() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  posted_.notify_all();
  for (std::thread& t : workers_) t.join();
}

std::size_t WorkerPool::worker_count() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return workers_.size();
}

void WorkerPool::add_workers(std::size_t wanted) {
  // One worker per core beside the caller: more parts than that wait for a free worker (or the caller)
  // rather than share a core. One core (or a count the system does not know): none, the caller runs all.
  const unsigned cores = std::thread::hardware_concurrency();
  const std::size_t most = cores > 1 ? cores - 1 : 0;
  while (!refused_ && workers_.size() < std::min(wanted, most)) {
    try {
      workers_.emplace_back([this] { work(); });
    } catch (const std::system_error&) {
      refused_ = true;  // the parts run on the workers there are, and on the caller
    }
  }
}

void WorkerPool::run(int parts, const std::function<void(int)>& task) {
  Batch batch;
  batch.task = &task;
  batch.parts = parts;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    add_workers(static_cast<std::size_t>(parts - 1));
    open_.push_back(&batch);
  }
  posted_.notify_all();
  for (int p = batch.next++; p < parts; p = batch.next++) {
    task(p);
    finish(batch);
  }
  std::unique_lock<std::mutex> lock(mutex_);
  // Every part is taken; the batch may still be listed (the caller took the last one): unlist it before
  // it goes out of scope, then wait for the parts workers are running.
  const auto listed = std::find(open_.begin(), open_.end(), &batch);
  if (listed != open_.end()) open_.erase(listed);
  finished_.wait(lock, [&] { return batch.finished == parts; });
}

void WorkerPool::finish(Batch& batch) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (++batch.finished == batch.parts) finished_.notify_all();
}

void WorkerPool::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    posted_.wait(lock, [&] { return stopping_ || !open_.empty(); });
    if (open_.empty()) return;  // stopping, nothing left
    Batch& batch = *open_.front();
    const int p = batch.next++;
    if (p >= batch.parts - 1) open_.pop_front();  // this was its last part, or none was left
    if (p >= batch.parts) continue;
    lock.unlock();
    (*batch.task)(p);
    lock.lock();
    if (++batch.finished == batch.parts) finished_.notify_all();
  }
}

}  // namespace occ_improve::detail
