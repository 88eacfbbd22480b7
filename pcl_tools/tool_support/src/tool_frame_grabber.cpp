#include "occ_improve/tools/tool_frame_grabber.hpp"

namespace occ_improve {

ToolFrameGrabber::ToolFrameGrabber(const ToolOptions& options, const ToolFrame& first, std::vector<FrameSource> sources,
                                   float fps)
    : FileSequenceGrabber(sources.size(), fps),
      options_(options),
      first_(frame_header(first)),
      sources_(std::move(sources)) {}

FileSequenceGrabber::Cloud::Ptr ToolFrameGrabber::loadFrame(std::size_t index) {
  ToolFrame frame = load_tool_frame(options_, sources_[index], &first_);
  require_same_camera(first_, frame);
  move_into_first_frame(options_, first_, frame);
  return Cloud::Ptr(new Cloud(std::move(frame.cloud)));
}

}  // namespace occ_improve
