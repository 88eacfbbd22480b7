#pragma once
// Segmenting an organized cloud through the occupancy grid: the cloud is inserted into a fresh map
// (Mapper: insertion, surface, improvement), the map is segmented per ray (segmentation.hpp), and every
// point takes the label of the ray (column) its direction falls in.
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/segmentation/segmentation.hpp"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <vector>

namespace occ_improve {

struct CloudSegmentation {
  std::vector<std::uint32_t> point_labels;  ///< per point of the cloud; 0 = invalid point or no segment
  Segmentation segmentation;                ///< per ray of the grid
  MapperReport mapping;                     ///< insertion / surface / improvement timings and counts
  double mapping_seconds = 0;               ///< fresh map + insertion + surface + improvement
  double segmentation_seconds = 0;          ///< segment_improvement
  double labelling_seconds = 0;             ///< rays -> points
  std::size_t points_outside_grid = 0;      ///< valid points whose direction lies outside the grid
  double total_seconds() const { return mapping_seconds + segmentation_seconds + labelling_seconds; }
};

/// Throws InvalidInput when the cloud is not organized (height <= 1): the method needs a range image.
/// A cloud without valid points gives no segments (not an error). With a `mask` (mask.hpp, the camera's
/// size), the points outside it are left out of the map (Mapper::set_mask) and labelled 0.
template <typename PointT>
CloudSegmentation segment_cloud(const pcl::PointCloud<PointT>& cloud, const SensorPreset& preset,
                                const SegmentationParams& params, const GridOptions& grid_options = {},
                                const PixelMask* mask = nullptr);

/// The per-ray labels carried to the points of an organized cloud (the column each point's direction
/// falls in). Counts valid points outside the grid in `outside`.
template <typename PointT>
std::vector<std::uint32_t> labels_for_points(const pcl::PointCloud<PointT>& cloud, const GridGeometry& geometry,
                                             const Segmentation& segmentation, std::size_t& outside);

}  // namespace occ_improve
