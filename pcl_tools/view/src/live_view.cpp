// The part of the live view that needs no window: the hand-over of frames from the pipeline's worker.
#include "occ_improve/tools/live_view.hpp"

#include <fstream>

namespace occ_improve {

bool is_live_view_screenshot(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head.rfind("\x89PNG\r\n\x1a\n", 0) == 0 && head.find(kLiveViewSoftware) != std::string::npos;
}

void LiveView::post(const ImprovementMap& map, std::vector<Region> top_regions, std::uint64_t frames) {
  LiveFrame frame{render_improvement(map), std::move(top_regions), frames};  // rendered outside the lock
  std::lock_guard<std::mutex> lock(mutex_);
  pending_ = std::move(frame);
}

std::optional<LiveFrame> LiveView::take() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<LiveFrame> frame = std::move(pending_);
  pending_.reset();
  return frame;
}

}  // namespace occ_improve
