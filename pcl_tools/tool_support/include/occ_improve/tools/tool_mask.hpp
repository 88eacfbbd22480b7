#pragma once
// A tool's -mask: a PNG of valid pixels, or "finite" (the first frame's valid pixels); every refusal is
// one line naming -mask and its value.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/tools/flags.hpp"
#include "occ_improve/tools/tool_frames.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// The -mask of a frame-reading tool (nullopt without it): the PNG (read_mask_png), or for "finite" the
/// valid pixels of `first`, which must be an organized frame of its camera's size. Refusals are one line
/// naming -mask and the file.
std::optional<PixelMask> read_tool_mask(const CommandLine& command_line, const ToolFrame* first);
/// read_tool_mask set on the mapper (Mapper::set_mask); refusals (another size than the camera, a grid
/// without a camera) name -mask and the file. Returns the summary line ("mask FILE: N of M pixels valid"),
/// "" without -mask.
std::string apply_tool_mask(const CommandLine& command_line, Mapper& mapper, const ToolFrame* first);
/// mask_columns(geometry, mask) with refusals naming -mask and the file: for a tool that checks the mask
/// before its mapper exists (occ_segment) or fills a grid itself (occ_to_octomap).
std::vector<std::uint8_t> tool_mask_columns(const CommandLine& command_line, const GridGeometry& geometry,
                                            const PixelMask& mask);

}  // namespace occ_improve
