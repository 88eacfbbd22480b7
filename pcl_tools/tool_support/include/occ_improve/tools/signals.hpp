#pragma once
// Stopping on SIGINT/SIGTERM: run_tool's handlers call the library's request_stop(signal) (cancel.hpp),
// so the library's long loops and the tools' own (frames, files, shots; throw_if_stop_requested) stop
// within milliseconds with Cancelled, which run_tool reports as "interrupted by SIG..." and exit code
// 128 + the signal. stop_requested() is the signal received, or 0. A second signal ends the process at
// once; one within 50 ms of the last is the same press delivered twice (coreutils' timeout signals the
// command and its process group) and is ignored.
#include "occ_improve/cancel.hpp"

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <utility>

namespace occ_improve {

/// Installs the SIGINT and SIGTERM handlers that request a stop (run_tool does, before the tool runs).
void install_stop_signals();

/// For a tool that still writes what it has after a stop (occ_improve_live): the signal received, or 0,
/// and the request withdrawn so that the writing is not cancelled too; the tool then ends with
/// throw Cancelled(signal). The frame or shot in flight when the signal came is left partly inserted.
int take_stop_request();

/// For a tool that finishes the work in flight on a first signal (occ_improve_live's frame, so that its map
/// holds whole frames): from now on a first SIGINT/SIGTERM is only recorded (soft_stop_signal()), and the
/// handlers become install_stop_signals' own, so that a second signal cancels the work in flight and a
/// third kills. The tool bounds the wait itself (CancelAfter).
void defer_first_stop_signal();
/// The signal a deferred first stop recorded, or 0.
int soft_stop_signal();

/// While it lives, after `timeout` requests a stop with `signal` (when non-zero), cancelling the work in
/// flight: the bound on what a first, deferred signal lets finish.
class CancelAfter {
public:
  CancelAfter(int signal, std::chrono::milliseconds timeout);
  CancelAfter(const CancelAfter&) = delete;
  CancelAfter& operator=(const CancelAfter&) = delete;
  ~CancelAfter();

private:
  std::mutex mutex_;
  std::condition_variable done_;
  bool finished_ = false;
  std::thread watchdog_;
};

/// Asks run_tool to end the process at once (std::_Exit) when the run ends, after the staged outputs were
/// removed or committed; whether it was asked.
void end_process_at_once();
bool process_ends_at_once();

/// Leaves `owned` (moved into a heap object never freed) to the process's end when the scope is left
/// after a stop request, and asks run_tool to end the process at once: freeing 10^7 nodes (an OcTree at
/// a fine resolution) or a large block after them (glibc then consolidates every small chunk freed
/// before: 0.5 s) takes longer than Ctrl-C may wait. Declare it after `owned`, so that it runs first.
template <typename T>
class LeftToExitOnStop {
public:
  explicit LeftToExitOnStop(T& owned) : owned_(owned) {}
  LeftToExitOnStop(const LeftToExitOnStop&) = delete;
  LeftToExitOnStop& operator=(const LeftToExitOnStop&) = delete;
  ~LeftToExitOnStop() {
    if (stop_requested() == 0) return;
    new T(std::move(owned_));  // NOLINT: left to the process's end on purpose
    end_process_at_once();
  }

private:
  T& owned_;
};

}  // namespace occ_improve
