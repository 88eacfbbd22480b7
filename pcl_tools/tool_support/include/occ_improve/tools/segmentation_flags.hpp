#pragma once
// The segmentation flags over a preset's segmentation defaults.
#include "occ_improve/segmentation/segmentation.hpp"
#include "occ_improve/tools/flags.hpp"

namespace occ_improve {

/// -contour, -min_segment, -plane_distance and -no_plane, those the tool declares and the user gave (or, for
/// -min_segment, its table default), over a preset's segmentation defaults (segmentation_defaults).
void apply_segmentation_flags(const CommandLine& command_line, SegmentationParams& params);

}  // namespace occ_improve
