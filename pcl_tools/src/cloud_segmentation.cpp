#include "occ_improve/pcl/cloud_segmentation.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/timing.hpp"

#include <cmath>

namespace occ_improve {

template <typename PointT>
std::vector<std::uint32_t> labels_for_points(const pcl::PointCloud<PointT>& cloud, const GridGeometry& geometry,
                                             const Segmentation& segmentation, std::size_t& outside) {
  require_shape("labels_for_points: segmentation", segmentation.shape(), "the grid",
                ColumnShape::of_grid(geometry.width(), geometry.height()));
  std::vector<std::uint32_t> labels(cloud.size(), 0);
  outside = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointT& p = cloud[i];
    if (!is_valid_point(p.x, p.y, p.z))
      continue;
    ColumnIndex column = 0;
    if (!geometry.column_of(p.x, p.y, p.z, column)) {
      ++outside;
      continue;
    }
    labels[i] = segmentation.label[column];
  }
  return labels;
}

template <typename PointT>
CloudSegmentation segment_cloud(const pcl::PointCloud<PointT>& cloud, const SensorPreset& preset,
                                const SegmentationParams& params, const GridOptions& grid_options,
                                const PixelMask* mask) {
  if (!cloud.isOrganized() || cloud.height <= 1)
    throw InvalidInput("the cloud is not organized (height 1): segmentation from the improvement map needs a "
                       "range image, i.e. an organized cloud");
  params.validate();
  using Clock = SteadyClock;
  CloudSegmentation result;
  auto start = Clock::now();
  Mapper mapper(preset, grid_options);
  if (mask) mapper.set_mask(*mask);
  result.mapping = mapper.insert(span_of(cloud));
  result.mapping_seconds = seconds_since(start);

  start = Clock::now();
  result.segmentation = segment_improvement(mapper.geometry(), mapper.surface(), mapper.improvement(), params);
  result.segmentation_seconds = seconds_since(start);

  start = Clock::now();
  result.point_labels = labels_for_points(cloud, mapper.geometry(), result.segmentation, result.points_outside_grid);
  if (mask && mask->valid.size() == result.point_labels.size())  // organized at the camera's size: pixel = point
    for (std::size_t i = 0; i < mask->valid.size(); ++i)
      if (!mask->valid[i]) result.point_labels[i] = 0;
  result.labelling_seconds = seconds_since(start);
  return result;
}

#define OCC_IMPROVE_INSTANTIATE_SEGMENT_CLOUD(T)                                                                  \
  template CloudSegmentation segment_cloud(const pcl::PointCloud<T>&, const SensorPreset&,                        \
                                           const SegmentationParams&, const GridOptions&, const PixelMask*);                         \
  template std::vector<std::uint32_t> labels_for_points(const pcl::PointCloud<T>&, const GridGeometry&,     \
                                                        const Segmentation&, std::size_t&);
OCC_IMPROVE_INSTANTIATE_SEGMENT_CLOUD(pcl::PointXYZ)
OCC_IMPROVE_INSTANTIATE_SEGMENT_CLOUD(pcl::PointXYZRGB)
OCC_IMPROVE_INSTANTIATE_SEGMENT_CLOUD(pcl::PointXYZRGBA)
OCC_IMPROVE_INSTANTIATE_SEGMENT_CLOUD(pcl::PointXYZRGBL)
#undef OCC_IMPROVE_INSTANTIATE_SEGMENT_CLOUD

}  // namespace occ_improve
