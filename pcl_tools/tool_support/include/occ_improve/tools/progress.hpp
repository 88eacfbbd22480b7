#pragma once
// The progress line of a tool's long work.
#include "occ_improve/tools/flags.hpp"

#include <cstddef>
#include <string>

namespace occ_improve {

/// A progress line on stderr for work that runs over about a second ("frame 12/50, 3.1M points,
/// 4.2 frames/s, 9 s left"). Shown only when stderr is a terminal and -q was not given (silent in logs and
/// pipes); redrawn at most ten times a second; erased by finish() or the destructor, so the summary that
/// follows starts on a clean line.
class ProgressLine {
public:
  /// `unit` names what is counted: "frame", "shot", "cloud".
  ProgressLine(const CommandLine& command_line, std::string unit);
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  ~ProgressLine();

  bool shown() const { return shown_; }
  /// `done` of `total` units (total 0: unknown) and the points handled so far; rate and time left follow.
  void update(std::size_t done, std::size_t total, std::size_t points = 0);
  /// A line of the tool's own making (a live stream's counters).
  void show(const std::string& text);
  void finish();

private:
  bool shown_;
  bool drawn_ = false;
  std::string unit_;
  double start_seconds_, last_draw_seconds_ = -1.0;
};

}  // namespace occ_improve
