#include "occ_improve/tools/progress.hpp"

#include "occ_improve/timing.hpp"

#include <unistd.h>

#include <cstdio>
#include <sstream>

namespace occ_improve {

ProgressLine::ProgressLine(const CommandLine& c, std::string unit)
    : shown_(isatty(fileno(stderr)) != 0 && !(c.declares("-q") && c.has("-q"))),
      unit_(std::move(unit)),
      start_seconds_(now_seconds()) {}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::show(const std::string& text) {
  if (!shown_) return;
  const double now = now_seconds();
  if (last_draw_seconds_ >= 0 && now - last_draw_seconds_ < 0.1) return;
  last_draw_seconds_ = now;
  std::fprintf(stderr, "\r\033[K%s", text.c_str());  // erase to the end of the line, then draw
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressLine::update(std::size_t done, std::size_t total, std::size_t points) {
  if (!shown_) return;
  const double elapsed = now_seconds() - start_seconds_;
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  std::ostringstream line;
  line.setf(std::ios::fixed);
  line.precision(1);
  line << unit_ << ' ' << done;
  if (total) line << '/' << total;
  if (points) line << ", " << static_cast<double>(points) / 1e6 << "M points";
  if (done) line << ", " << rate << ' ' << unit_ << "s/s";
  if (total && done && done < total) line << ", " << static_cast<double>(total - done) / rate << " s left";
  show(line.str());
}

void ProgressLine::finish() {
  if (!drawn_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
  drawn_ = false;
}

}  // namespace occ_improve
