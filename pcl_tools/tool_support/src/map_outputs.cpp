#include "occ_improve/tools/map_outputs.hpp"

#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/map_cloud.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace occ_improve {

namespace {

constexpr double kRadToDeg = 57.29577951308232;

// Directions and angles are written for both binnings: the angles are those of the unit direction
// (CONVENTIONS 1: azimuth atan2(x, z), elevation atan2(y, hypot(x, z)), y down), so they are degrees with the
// pixel-native presets too, never pixel positions.
void write_regions_csv(const std::string& path, const std::vector<Region>& regions) {
  std::string out = "rank,summed_improvement,area_columns,peak_improvement,centre_u,centre_v,peak_u,peak_v,min_u,min_v,max_u,"
         "max_v,direction_x,direction_y,direction_z,azimuth_deg,elevation_deg,mean_depth_m\n";
  char line[512];
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const Region& r = regions[i];
    std::snprintf(line, sizeof line, "%zu,%.6f,%zu,%.6f,%d,%d,%d,%d,%d,%d,%d,%d,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f\n", i + 1,
                  r.summed_improvement, r.area_columns, static_cast<double>(r.peak_improvement), r.centre_u, r.centre_v,
                  r.peak_u, r.peak_v, r.min_u, r.min_v, r.max_u, r.max_v, r.centre_direction.x(),
                  r.centre_direction.y(), r.centre_direction.z(), r.centre_azimuth_rad * kRadToDeg,
                  r.centre_elevation_rad * kRadToDeg, r.mean_depth_m);
    out += line;
  }
  write_text_file(path, "CSV file", out);
}

void write_rays_csv(const std::string& path, const GridGeometry& geometry, const std::vector<RankedRay>& rays) {
  std::string out = "rank,improvement,column_u,row_v,direction_x,direction_y,direction_z,azimuth_deg,elevation_deg,depth_m\n";
  char line[256];
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RankedRay& r = rays[i];
    const Eigen::Vector3d d = geometry.direction(r.azimuth_bin, r.elevation_bin);
    const SphericalPoint angles = to_spherical(d.x(), d.y(), d.z());
    std::snprintf(line, sizeof line, "%zu,%.6f,%d,%d,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f\n", i + 1,
                  static_cast<double>(r.improvement), r.azimuth_bin, r.elevation_bin, d.x(), d.y(), d.z(),
                  angles.azimuth * kRadToDeg, angles.elevation * kRadToDeg, static_cast<double>(r.depth_m));
    out += line;
  }
  write_text_file(path, "CSV file", out);
}

// Depths in metres as 16-bit millimetres, rounded: 0 where `known(column)` is false or the depth rounds to
// 0; depths beyond 65.535 m saturate at 65535 (depth_mm.png, predicted_depth.png).
template <typename Known>
Image16 millimetres_image(int width, int height, const std::vector<float>& depth_m, const Known& known) {
  Image16 image{width, height, std::vector<std::uint16_t>(depth_m.size(), 0)};
  for (std::size_t c = 0; c < depth_m.size(); ++c) {
    const double mm = std::round(static_cast<double>(depth_m[c]) * 1000.0);
    if (known(c) && mm > 0) image.pixels[c] = static_cast<std::uint16_t>(std::min(mm, 65535.0));
  }
  return image;
}

}  // namespace

MapSummary summarize_map(const Mapper& mapper, const RegionOptions& region_options, int top_k) {
  MapSummary s;
  s.all_regions = find_regions(mapper.geometry(), mapper.improvement(), mapper.surface(), region_options);
  s.rays = top_rays(mapper.improvement(), mapper.surface(), top_k);
  s.stop = stop_signal(mapper.improvement(), s.all_regions);
  s.region_options = region_options;
  const std::size_t k = std::min(s.all_regions.size(), static_cast<std::size_t>(top_k));
  s.regions.assign(s.all_regions.begin(), s.all_regions.begin() + static_cast<std::ptrdiff_t>(k));
  return s;
}

Image16 depth_millimetres(const SurfaceMap& surface) {
  return millimetres_image(surface.width, surface.height, surface.depth_m,
                           [&](std::size_t c) { return surface.unknown[c] == 0; });
}

Image16 region_id_image(const Mapper& mapper, const MapSummary& summary) {
  if (summary.regions.size() > 65535)
    throw InvalidParameter("regions.png holds 16-bit region ids: " + std::to_string(summary.regions.size()) +
                           " regions are too many (lower -k to at most 65535)");
  const std::vector<std::uint32_t> labels =
      region_labels(mapper.geometry(), mapper.improvement(), summary.regions, summary.region_options);
  Image16 image{mapper.geometry().width(), mapper.geometry().height(), std::vector<std::uint16_t>(labels.size())};
  std::copy(labels.begin(), labels.end(), image.pixels.begin());
  return image;
}

std::vector<std::string> write_map_outputs(OutputFolder& out, const Mapper& mapper, const MapSummary& summary,
                                           const std::optional<Image>& colour) {
  std::vector<std::string> names;
  const auto png = [&](const std::string& name, const Image& image) {
    write_png(out.file(name), image);
    names.push_back(name);
  };
  png("depth.png", render_depth(mapper.surface(), mapper.geometry().depth().max()));
  write_png(out.file("depth_mm.png"), depth_millimetres(mapper.surface()));
  names.push_back("depth_mm.png");
  png("occupancy.png", render_occupancy(mapper.surface()));
  png("improvement.png", render_improvement(mapper.improvement()));
  png("legend.png", render_improvement_legend());
  if (colour && mapper.geometry().binning() == AngularBinning::pinhole)
    png("overlay.png", render_overlay(mapper.improvement(), *colour));
  save_improvement_cloud(out.file("surface.pcd"),
                         to_improvement_cloud(mapper.geometry(), mapper.surface(), mapper.improvement()));
  write_regions_csv(out.file("regions.csv"), summary.regions);
  write_png(out.file("regions.png"), region_id_image(mapper, summary));
  write_rays_csv(out.file("rays.csv"), mapper.geometry(), summary.rays);
  names.insert(names.end(), {"surface.pcd", "regions.csv", "regions.png", "rays.csv"});
  return names;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : " ") + n;
  return text;
}

std::string write_predicted_depth(OutputFolder& out, const Mapper& mapper, const std::string& rule, int radius_columns) {
  if (rule == "none") return "";
  if (rule != "nearest" && rule != "linear")
    throw InvalidParameter("-predicted_depth " + rule + " is invalid: must be none, nearest or linear");
  DepthPredictionParams params;
  params.rule = rule == "linear" ? DepthPredictionRule::linear : DepthPredictionRule::nearest;
  params.radius_columns = radius_columns;
  const PredictedDepth p = predict_depth(mapper.surface(), mapper.model(), params);
  write_png(out.file("predicted_depth.png"),
            millimetres_image(p.width, p.height, p.depth_m, [&](std::size_t c) { return p.distance[c] >= 0; }));
  return "predicted_depth.png";
}

}  // namespace occ_improve
