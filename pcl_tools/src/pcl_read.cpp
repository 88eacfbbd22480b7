// PCL's readers on a thread of their own, so that a stop request is obeyed while they read (header_text.hpp).
#include "header_text.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/pcl/frame_io.hpp"

#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <thread>

namespace occ_improve {

namespace {

std::atomic<bool> g_read_abandoned{false};

// Shared by the caller and the reading thread: whichever ends last frees it.
struct ReadState {
  detail::PclRead result;
  int status = 0;
  std::exception_ptr error;
  std::promise<void> done;
};

}  // namespace

bool pcl_read_abandoned() { return g_read_abandoned.load(); }

namespace detail {

PclRead read_or_throw(const std::string& path, const char* format, std::function<int(PclRead&)> read) {
  auto state = std::make_shared<ReadState>();
  std::future<void> done = state->done.get_future();
  std::thread([state, read = std::move(read)] {
    try {
      state->status = read(state->result);
    } catch (...) {
      state->error = std::current_exception();
    }
    state->done.set_value();
  }).detach();
  while (done.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
    if (stop_requested() != 0) {
      g_read_abandoned = true;
      throw_if_stop_requested();
    }
  }
  const std::string unreadable = "'" + path + "' is not a readable " + format + " file";
  if (state->error) {
    try {
      std::rethrow_exception(state->error);
    } catch (const std::bad_alloc&) {
      throw;
    } catch (const std::exception& e) {
      throw FormatError(unreadable + " (PCL's reader: " + e.what() + ")");
    }
  }
  if (state->status < 0) throw FormatError(unreadable);
  return std::move(state->result);
}

}  // namespace detail
}  // namespace occ_improve
