#include "occ_improve/pcl/improvement_filter.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/ranking.hpp"

#include <pcl/filters/impl/filter_indices.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace occ_improve {

template <typename PointT>
ImprovementFilter<PointT>::ImprovementFilter(bool extract_removed_indices)
    : pcl::FilterIndices<PointT>(extract_removed_indices), mapper_(std::make_shared<Mapper>(kinect_v1())) {
  filter_name_ = "ImprovementFilter";
}

template <typename PointT>
void ImprovementFilter<PointT>::setSensorPreset(const SensorPreset& preset, const GridOptions& grid_options) {
  mapper_ = std::make_shared<Mapper>(preset, grid_options);
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
bool ImprovementFilter<PointT>::evaluate(std::vector<float>& point_improvement) {
  const auto& cloud = *input_;
  last_report_ = {};
  if (update_map_) {
    try {
      if (indices_->size() == cloud.size()) {
        last_report_ = mapper_->insert(span_of(cloud), insertion_options_);
      } else {
        std::vector<Eigen::Vector3f> points;
        points.reserve(indices_->size());
        for (const auto i : *indices_) points.emplace_back(cloud[i].x, cloud[i].y, cloud[i].z);
        last_report_ = mapper_->insert(PointSpan::from(points), insertion_options_);
      }
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
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointT& p = cloud[i];
    PointImprovement& out = improvement_cloud_[i];
    out.x = p.x;
    out.y = p.y;
    out.z = p.z;
    out.surface_depth = out.probability = out.improvement = nan;
    ColumnIndex column = 0;
    if (!geometry.column_of(p.x, p.y, p.z, column)) continue;
    out.surface_depth = surface.depth_m[column];
    out.probability = surface.probability[column];
    out.improvement = improvement.value[column];
    point_improvement[i] = out.improvement;
  }
  return true;
}

template <typename PointT>
pcl::Indices ImprovementFilter<PointT>::select(const std::vector<float>& point_improvement) const {
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
      const std::size_t keep =
          selection_ == ImprovementSelection::top_count
              ? std::min(top_count_, with_ray.size())
              : static_cast<std::size_t>(std::llround(top_fraction_ * static_cast<double>(with_ray.size())));
      selected = stratified_top(with_ray, point_improvement, keep);
      std::sort(selected.begin(), selected.end());  // back to ascending index order like every PCL filter
      return selected;
    }
  }
  return selected;
}

// The top modes' order (header: "Top modes"): a jittered grid at the scale of the sampling, with the
// improvement choosing inside each cell and among the cells of the last, partial round.
template <typename PointT>
pcl::Indices ImprovementFilter<PointT>::stratified_top(const pcl::Indices& with_ray,
                                                       const std::vector<float>& point_improvement,
                                                       std::size_t keep) const {
  if (keep == 0) return {};
  const ImprovementPyramid& pyramid = mapper_->pyramid();
  const GridGeometry& geometry = mapper_->geometry();
  const SurfaceMap& surface = mapper_->surface();
  struct Candidate {
    bool sampled;  ///< its ray holds a depth sample (is_depth_sample)
    float improvement, block_mean;
    std::uint64_t ray_key, point_key;
    ColumnIndex column;
    std::size_t cell;      ///< its SamplingCells cell
    std::uint32_t repeat;  ///< how many points of the same ray come before it
    std::uint32_t round;   ///< its rank within its cell: the round that takes it
    pcl::index_t index;
  };
  std::vector<Candidate> candidates;
  candidates.reserve(with_ray.size());
  std::vector<std::uint32_t> points_of_ray(geometry.column_count(), 0);
  std::size_t rays = 0;
  for (const auto i : with_ray) {
    const PointT& p = (*input_)[static_cast<std::size_t>(i)];
    ColumnIndex column = 0;
    geometry.column_of(p.x, p.y, p.z, column);  // has a ray: point_improvement[i] is not NaN
    const float block_mean = pyramid.block_at(kTieLevel, pyramid.block_of_column(kTieLevel, column)).mean_improvement();
    const std::uint32_t repeat = points_of_ray[column]++;
    if (repeat == 0) ++rays;
    const float value = point_improvement[static_cast<std::size_t>(i)];
    candidates.push_back({is_depth_sample(surface, column), value, block_mean, rank_key(value, column),
                          rank_key(0.0f, static_cast<ColumnIndex>(i)), column, 0, repeat, 0, i});
  }
  // About one kept point per cell (the cells need the count of distinct rays, known only now).
  const SamplingCells cells(rays, keep, geometry.width());
  for (Candidate& c : candidates) c.cell = cells.cell_of(geometry.azimuth_bin_of(c.column), geometry.elevation_bin_of(c.column));
  // Better first, by ray (header, "better"): a ray with a sample, then the ray's improvement, its block's
  // mean improvement, its spread rank, then the point's own spread rank.
  const auto better = [](const Candidate& a, const Candidate& b) {
    if (a.sampled != b.sampled) return a.sampled;
    if (a.improvement != b.improvement) return a.improvement > b.improvement;
    if (a.block_mean != b.block_mean) return a.block_mean > b.block_mean;
    if (a.ray_key != b.ray_key) return a.ray_key > b.ray_key;
    return a.point_key > b.point_key;
  };
  // Within a cell: distinct rays before a second point of one ray, then better first.
  std::sort(candidates.begin(), candidates.end(), [&](const Candidate& a, const Candidate& b) {
    if (a.cell != b.cell) return a.cell < b.cell;
    if (a.repeat != b.repeat) return a.repeat < b.repeat;
    return better(a, b);
  });
  for (std::size_t k = 0; k < candidates.size(); ++k)
    candidates[k].round = k > 0 && candidates[k - 1].cell == candidates[k].cell ? candidates[k - 1].round + 1 : 0;
  // Round by round; within a round, the cells whose candidate is better first.
  const auto last = candidates.begin() + static_cast<std::ptrdiff_t>(std::min(keep, candidates.size()));
  std::partial_sort(candidates.begin(), last, candidates.end(), [&](const Candidate& a, const Candidate& b) {
    if (a.round != b.round) return a.round < b.round;
    return better(a, b);
  });
  pcl::Indices selected;
  selected.reserve(keep);
  for (auto c = candidates.begin(); c != last; ++c) selected.push_back(c->index);
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
  if (!ok || !evaluate(point_improvement)) {
    // Nothing selected: every considered point counts as removed (keep-organized output is all NaN).
    if (extract_removed_indices_) *removed_indices_ = *indices_;
    return;
  }

  for (const auto i : *indices_)
    if (std::isnan(point_improvement[i])) ++points_without_ray_;
  const pcl::Indices selected = select(point_improvement);

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
