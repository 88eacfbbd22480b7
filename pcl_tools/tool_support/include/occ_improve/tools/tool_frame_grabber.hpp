#pragma once
// The positional inputs of occ_improve_live as a grabber: every input kind the other tools read (PCD, PLY,
// depth PNG/PGM/TIFF, dataset folders), replayed in order by the file-sequence machinery (pacing, counting,
// clean stop) with the tools' frame rules (load_tool_frame).
#include "occ_improve/pcl/sequence_sources.hpp"
#include "occ_improve/tools/tool_frames.hpp"

#include <string>
#include <vector>

namespace occ_improve {

class ToolFrameGrabber : public FileSequenceGrabber {
public:
  /// `options` must outlive the grabber. Frames seen through another camera than `first`'s are refused
  /// (a source error, counted); with poses every frame is moved into `first`'s sensor frame
  /// (move_into_first_frame). fps = 0: as fast as possible.
  ToolFrameGrabber(const ToolOptions& options, const ToolFrame& first, std::vector<FrameSource> sources, float fps);
  ~ToolFrameGrabber() noexcept override { stop(); }
  std::string getName() const override { return "ToolFrameGrabber"; }

protected:
  Cloud::Ptr loadFrame(std::size_t index) override;
  std::string frameName(std::size_t index) const override { return sources_[index].path; }

private:
  const ToolOptions& options_;
  ToolFrame first_;  ///< its name, camera and pose (the cloud is not kept)
  std::vector<FrameSource> sources_;
};

}  // namespace occ_improve
