#pragma once
// The per-ray results as an organized PCL cloud: one PointImprovement per ray of the grid, laid out
// like the maps (width = azimuth bins, height = elevation bins), so pcl_viewer and PCL filters can use
// the improvement as a field.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/pcl/point_types.hpp"
#include "occ_improve/maps/surface.hpp"

#include <pcl/point_cloud.h>

#include <string>

namespace occ_improve {

/// One point per ray at its surface depth along the ray's centre; x, y, z are NaN where the ray is
/// unknown (never observed), its surface_depth 0, probability 0.5, and its improvement kept. The cloud
/// is organized (width x height) and not dense. Throws InvalidInput when the maps do not match the
/// geometry.
pcl::PointCloud<PointImprovement> to_improvement_cloud(const GridGeometry& geometry, const SurfaceMap& surface,
                                                       const ImprovementMap& improvement);

/// Writes the cloud as a binary PCD. Throws IoError when the file cannot be written.
void save_improvement_cloud(const std::string& path, const pcl::PointCloud<PointImprovement>& cloud);

}  // namespace occ_improve
