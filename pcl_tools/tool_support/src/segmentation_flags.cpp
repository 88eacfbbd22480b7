#include "occ_improve/tools/segmentation_flags.hpp"

namespace occ_improve {

void apply_segmentation_flags(const CommandLine& c, SegmentationParams& params) {
  if (c.declares("-contour") && c.has("-contour"))
    params.contour_improvement_below = static_cast<float>(*c.number("-contour"));
  if (c.declares("-min_segment")) params.min_segment_columns = static_cast<std::size_t>(*c.integer("-min_segment"));
  if (c.declares("-plane_distance") && c.has("-plane_distance")) params.plane_distance_m = *c.number("-plane_distance");
  if (c.declares("-no_plane") && c.has("-no_plane")) params.remove_dominant_plane = false;
  if (c.declares("-no_crease") && c.has("-no_crease")) params.split_concave_creases = false;
  params.validate();
}

}  // namespace occ_improve
