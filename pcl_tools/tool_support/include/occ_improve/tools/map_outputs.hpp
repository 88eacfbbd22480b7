#pragma once
// The files a tool writes for an improvement map, with the same names and columns in every tool
// (occ_improve_map, occ_improve_live): depth.png depth_mm.png occupancy.png improvement.png legend.png
// [overlay.png] surface.pcd regions.csv regions.png rays.csv. README "Output files" documents every column.
#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sim/render.hpp"

#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// What the map says: its regions (all, and the top K), its best rays and the stop signal.
struct MapSummary {
  std::vector<Region> all_regions;  ///< every region, best first
  std::vector<Region> regions;      ///< the first K of them
  std::vector<RankedRay> rays;      ///< the K best single rays
  StopSignal stop{false, 0.0, 0.0, ""};
  RegionOptions region_options;     ///< what the regions were found with (regions.png grows them again)
};

MapSummary summarize_map(const Mapper& mapper, const RegionOptions& regions, int top_k);

/// Writes the map's files into `out` (staged: the caller commits). overlay.png only when `colour` is given
/// and the grid is pixel-native (its columns are then the colour image's pixels). Returns the file names
/// written, in order, for the tool's "wrote" line.
std::vector<std::string> write_map_outputs(OutputFolder& out, const Mapper& mapper, const MapSummary& summary,
                                           const std::optional<Image>& colour);

/// The surface depth of each ray in millimetres, rounded, 0 where unknown (depth_mm.png): z with the
/// pixel-native presets, so the file reads back as a 16-bit depth image; the range with spherical ones.
Image16 depth_millimetres(const SurfaceMap& surface);
/// The region ids of regions.csv per column (regions.png): its row's rank, 0 outside every listed region.
/// Throws InvalidParameter for more than 65535 regions (a 16-bit id; lower -k).
Image16 region_id_image(const Mapper& mapper, const MapSummary& summary);

/// -predicted_depth RULE (none, nearest, linear) with -radius R: the map's dense predicted depth from its
/// surface samples (depth_prediction.hpp) into `out` as predicted_depth.png, 16-bit grey in millimetres
/// (rounded; 0 = no prediction within the radius; depths beyond 65.535 m are written as 65535), one pixel
/// per column, so aligned with the depth image for the pixel-native presets. Returns the file name, or ""
/// for none.
std::string write_predicted_depth(OutputFolder& out, const Mapper& mapper, const std::string& rule, int radius_columns);

/// "a b c" for a list of file names.
std::string join_names(const std::vector<std::string>& names);

}  // namespace occ_improve
