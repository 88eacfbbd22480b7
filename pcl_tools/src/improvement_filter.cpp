#include "occ_improve/pcl/improvement_filter.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/planning/point_selection.hpp"
#include "occ_improve/sensor/intrinsics_fit.hpp"
#include "occ_improve/sensor/presets.hpp"

#include <pcl/filters/impl/filter_indices.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace occ_improve {
namespace {

// Indices 0, 1, ..., count - 1 in order: the whole cloud, inserted in place (a list of that length may
// repeat or leave out points).
bool is_every_index(const pcl::Indices& indices, std::size_t count) {
  if (indices.size() != count) return false;
  for (std::size_t k = 0; k < count; ++k)
    if (indices[k] != static_cast<pcl::index_t>(k)) return false;
  return true;
}

}  // namespace

template <typename PointT>
ImprovementFilter<PointT>::ImprovementFilter(bool extract_removed_indices)
    : pcl::FilterIndices<PointT>(extract_removed_indices), mapper_(std::make_shared<Mapper>(kinect_v1())) {
  filter_name_ = "ImprovementFilter";
}

template <typename PointT>
void ImprovementFilter<PointT>::setSensorPreset(const SensorPreset& preset, const GridOptions& grid_options) {
  mapper_ = std::make_shared<Mapper>(preset, grid_options);
  camera_assumed_ = false;
}

template <typename PointT>
void ImprovementFilter<PointT>::fitDefaultCamera() {
  const auto& cloud = *input_;
  if (!camera_assumed_ || cloud.height <= 1 || mapper_->grid().touched_column_count() != 0 ||
      mapper_->geometry().binning() != AngularBinning::pinhole)
    return;
  camera_assumed_ = false;
  try {
    const PinholeIntrinsics fitted = estimate_intrinsics_fit(cloud, kMaxIntrinsicsFitResidualPx).intrinsics;
    if (!same_camera(fitted, *mapper_->geometry().params().camera)) mapper_ = std::make_shared<Mapper>(kinect_v1(fitted));
  } catch (const InvalidInput& e) {  // not a pinhole range image as it is (a registered or resampled cloud)
    PCL_WARN("[occ_improve::%s::applyFilter] the cloud's camera cannot be fitted (%s): the default map keeps Kinect "
             "v1's nominal camera; give setSensorPreset(kinect_v1(intrinsics)) for the cloud's own.\n",
             getClassName().c_str(), e.what());
  }
}

template <typename PointT>
void ImprovementFilter<PointT>::setImprovementRange(float min_improvement, float max_improvement) {
  selection_ = ImprovementSelection::range;
  min_improvement_ = min_improvement;
  max_improvement_ = max_improvement;
}

template <typename PointT>
void ImprovementFilter<PointT>::setTopCount(std::size_t count) {
  selection_ = ImprovementSelection::top_count;
  top_count_ = count;
}

template <typename PointT>
void ImprovementFilter<PointT>::setTopFraction(double fraction) {
  selection_ = ImprovementSelection::top_fraction;
  top_fraction_ = fraction;
}

template <typename PointT>
void ImprovementFilter<PointT>::setContourThreshold(float threshold) {
  selection_ = ImprovementSelection::contour;
  contour_threshold_ = threshold;
}

template <typename PointT>
bool ImprovementFilter<PointT>::parametersValid() const {
  switch (selection_) {
    case ImprovementSelection::range:
      if (std::isnan(min_improvement_) || std::isnan(max_improvement_) || min_improvement_ > max_improvement_) {
        PCL_ERROR("[occ_improve::%s::applyFilter] improvement range [%g, %g] is invalid: need min <= max.\n",
                  getClassName().c_str(), min_improvement_, max_improvement_);
        return false;
      }
      return true;
    case ImprovementSelection::top_fraction:
      if (!(top_fraction_ >= 0.0 && top_fraction_ <= 1.0)) {
        PCL_ERROR("[occ_improve::%s::applyFilter] top fraction %g is invalid: must be in [0, 1].\n",
                  getClassName().c_str(), top_fraction_);
        return false;
      }
      return true;
    case ImprovementSelection::contour:
      if (std::isnan(contour_threshold_)) {
        PCL_ERROR("[occ_improve::%s::applyFilter] contour threshold is NaN.\n", getClassName().c_str());
        return false;
      }
      return true;
    case ImprovementSelection::top_count:
      return true;
  }
  return false;
}

template <typename PointT>
bool ImprovementFilter<PointT>::evaluate(std::vector<float>& point_improvement, std::vector<ColumnIndex>& point_column) {
  const auto& cloud = *input_;
  last_report_ = {};
  fitDefaultCamera();
  // An organized cloud of another size than the map's camera is another camera's image: its points were
  // inserted without a word (GrabberPipeline rejects such a frame). Refused as the pipeline does.
  const std::optional<PinholeIntrinsics>& camera = mapper_->geometry().params().camera;
  if (cloud.height > 1 && mapper_->geometry().binning() == AngularBinning::pinhole && camera &&
      (static_cast<int>(cloud.width) != camera->width || static_cast<int>(cloud.height) != camera->height)) {
    PCL_ERROR("[occ_improve::%s::applyFilter] the organized cloud is %ux%u, the map's camera %dx%d: another camera's "
              "image (give setSensorPreset the cloud's own camera).\n",
              getClassName().c_str(), cloud.width, cloud.height, camera->width, camera->height);
    return false;
  }
  if (update_map_) {
    try {
      if (is_every_index(*indices_, cloud.size())) {
        last_report_ = mapper_->insert(span_of(cloud), insertion_options_);
      } else {
        std::vector<Eigen::Vector3f> points;
        points.reserve(indices_->size());
        for (const auto i : *indices_) points.emplace_back(cloud[i].x, cloud[i].y, cloud[i].z);
        last_report_ = mapper_->insert(PointSpan::from(points), insertion_options_);
      }
    } catch (const Cancelled&) {
      throw;  // the user's stop (header), not a cloud the map refuses
    } catch (const std::exception& e) {
      PCL_ERROR("[occ_improve::%s::applyFilter] cannot insert the cloud: %s\n", getClassName().c_str(), e.what());
      return false;
    }
  }

  const GridGeometry& geometry = mapper_->geometry();
  const SurfaceMap& surface = mapper_->surface();
  const ImprovementMap& improvement = mapper_->improvement();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  improvement_cloud_.resize(cloud.size());
  improvement_cloud_.width = cloud.width;
  improvement_cloud_.height = cloud.height;
  improvement_cloud_.is_dense = false;
  improvement_cloud_.header = cloud.header;
  point_improvement.assign(cloud.size(), nan);
  point_column.assign(cloud.size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointT& p = cloud[i];
    PointImprovement& out = improvement_cloud_[i];
    out.x = p.x;
    out.y = p.y;
    out.z = p.z;
    out.surface_depth = out.probability = out.improvement = nan;
    ColumnIndex column = 0;
    if (!geometry.column_of(p.x, p.y, p.z, column)) continue;
    point_column[i] = column;
    out.surface_depth = surface.depth_m[column];
    out.probability = surface.probability[column];
    out.improvement = improvement.value[column];
    point_improvement[i] = out.improvement;
  }
  return true;
}

template <typename PointT>
pcl::Indices ImprovementFilter<PointT>::select(const std::vector<float>& point_improvement,
                                               const std::vector<ColumnIndex>& point_column) const {
  pcl::Indices with_ray;
  with_ray.reserve(indices_->size());
  for (const auto i : *indices_)
    if (!std::isnan(point_improvement[i])) with_ray.push_back(i);

  pcl::Indices selected;
  switch (selection_) {
    case ImprovementSelection::range:
      for (const auto i : with_ray)
        if (point_improvement[i] >= min_improvement_ && point_improvement[i] <= max_improvement_) selected.push_back(i);
      return selected;
    case ImprovementSelection::contour:
      for (const auto i : with_ray)
        if (point_improvement[i] < contour_threshold_) selected.push_back(i);
      return selected;
    case ImprovementSelection::top_count:
    case ImprovementSelection::top_fraction: {
      // with_ray holds the observable points: the base keep_points_by_map counts a fraction of.
      selected = stratified_top(with_ray, point_column, selection_ == ImprovementSelection::top_count
                                              ? KeepAmount::count(top_count_)
                                              : KeepAmount::fraction(top_fraction_));
      return selected;
    }
  }
  return selected;
}

// The top modes' order (header: "Top modes"): keep_points_by_map (point_selection.hpp) over the points
// that have a ray.
template <typename PointT>
pcl::Indices ImprovementFilter<PointT>::stratified_top(const pcl::Indices& with_ray,
                                                       const std::vector<ColumnIndex>& point_column,
                                                       KeepAmount amount) const {
  std::vector<PointOnRay> points;
  points.reserve(with_ray.size());
  for (const auto i : with_ray) points.push_back({static_cast<std::uint64_t>(i), point_column[static_cast<std::size_t>(i)]});
  const MapView map{mapper_->geometry(), mapper_->surface(), mapper_->improvement(), mapper_->pyramid()};
  pcl::Indices selected;  // ascending, like every PCL filter's: keep_points_by_map returns the ids so
  for (const std::uint64_t i : keep_points_by_map(points, amount, map)) selected.push_back(static_cast<pcl::index_t>(i));
  return selected;
}

template <typename PointT>
void ImprovementFilter<PointT>::applyFilter(pcl::Indices& indices) {
  indices.clear();
  removed_indices_->clear();
  points_without_ray_ = 0;
  const bool ok = [&] {
    if (!mapper_) {
      PCL_ERROR("[occ_improve::%s::applyFilter] no map: call setSensorPreset() or setMapper() first.\n",
                getClassName().c_str());
      return false;
    }
    return parametersValid();
  }();
  std::vector<float> point_improvement;
  std::vector<ColumnIndex> point_column;
  if (!ok || !evaluate(point_improvement, point_column)) {
    // Nothing selected: every considered point counts as removed (keep-organized output is all NaN).
    if (extract_removed_indices_) *removed_indices_ = *indices_;
    return;
  }

  for (const auto i : *indices_)
    if (std::isnan(point_improvement[i])) ++points_without_ray_;
  const pcl::Indices selected = select(point_improvement, point_column);

  // Walk the considered indices once, in their order: a point goes to the output when it is selected
  // (normal) or has a ray and is not selected (negative); everything else is removed.
  std::vector<std::uint8_t> is_selected(input_->size(), 0);
  for (const auto i : selected) is_selected[i] = 1;
  indices.reserve(negative_ ? indices_->size() - selected.size() : selected.size());
  for (const auto i : *indices_) {
    const bool has_ray = !std::isnan(point_improvement[i]);
    const bool keep = has_ray && (negative_ ? !is_selected[i] : is_selected[i]);
    if (keep)
      indices.push_back(i);
    else if (extract_removed_indices_)
      removed_indices_->push_back(i);
  }
}

template <typename PointT>
pcl::Indices keep_most_improving(const pcl::PointCloud<PointT>& frame, const std::shared_ptr<Mapper>& mapper,
                                 double fraction) {
  detail::require_parameter(fraction >= 0.0 && fraction <= 1.0, "fraction", fraction, "in [0, 1]");
  if (!mapper) throw InvalidParameter("keep_most_improving: mapper is null");
  mapper->insert(span_of(frame));  // throws for a cloud it cannot take; the filter then only reads the map
  ImprovementFilter<PointT> filter;
  filter.setMapper(mapper);
  filter.setUpdateMap(false);
  filter.setTopFraction(fraction);
  filter.setInputCloud(typename pcl::PointCloud<PointT>::ConstPtr(&frame, [](const pcl::PointCloud<PointT>*) {}));
  pcl::Indices kept;
  filter.filter(kept);
  return kept;
}

#define OCC_IMPROVE_INSTANTIATE_FILTER(T)                                                                    \
  template class ImprovementFilter<T>;                                                                      \
  template pcl::Indices keep_most_improving<T>(const pcl::PointCloud<T>&, const std::shared_ptr<Mapper>&, double);

OCC_IMPROVE_INSTANTIATE_FILTER(pcl::PointXYZ)
OCC_IMPROVE_INSTANTIATE_FILTER(pcl::PointXYZI)
OCC_IMPROVE_INSTANTIATE_FILTER(pcl::PointXYZRGB)
OCC_IMPROVE_INSTANTIATE_FILTER(pcl::PointXYZRGBA)
OCC_IMPROVE_INSTANTIATE_FILTER(pcl::PointXYZL)

#undef OCC_IMPROVE_INSTANTIATE_FILTER

}  // namespace occ_improve
