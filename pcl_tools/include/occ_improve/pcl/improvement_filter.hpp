#pragma once
// ImprovementFilter: a PCL filter that keeps the points of a frame by the improvement of the ray they
// fall in. Fed a cloud from the sensor model's sensor (sensor frame), it first inserts the cloud into
// its Mapper (its own, or one shared through setMapper; setUpdateMap(false) only reads the map), then
// selects points by one of:
//  - range:         improvement in [min, max];
//  - top_count:     K points, in the top modes' order below;
//  - top_fraction:  that share of the points that have a ray, in the same order ("selective sensing":
//                   keep the share of a frame worth keeping, cut the data where it adds least);
//  - contour:       improvement < threshold (negative improvement marks depth discontinuities).
// Per-point improvement = the improvement of the ray (column) the point's direction falls in.
// Top modes (top_count, top_fraction): keep_points_by_map (occ_improve/planning/point_selection.hpp) over
// the points that have a ray: a jittered grid at the scale of the sampling, in each cell a ray that holds
// a depth sample before one that does not, then the improvement; ties spread over the view, never by
// point index. With setUpdateMap(true) the frame was inserted before the choice, so nearly every
// candidate holds a sample and the improvement decides; to thin a stream by the map, choose with
// setUpdateMap(false) and insert what is kept (docs/PIPELINE.md).
//
// Points without a ray (NaN/Inf, rho = 0, direction outside the grid's field of view) are never kept,
// neither in the normal nor in the negative (setNegative) output, like NaN points in pcl::PassThrough;
// they are always among the removed indices and are counted (getPointsWithoutRay()).
// setNegative, setKeepOrganized, setUserFilterValue and getRemovedIndices behave as in every
// pcl::FilterIndices. Errors (no map, bad parameters, a map the cloud cannot be inserted into) follow
// PCL's convention: PCL_ERROR and an empty selection. A stop request (Ctrl-C, cancel.hpp) is not an
// error: filter() throws occ_improve::Cancelled, as every long call of the library does.
//
// getImprovementCloud(): per input point (aligned with the input cloud, same width/height) its x y z,
// and the surface depth, surface probability and improvement of its ray (NaN where it has no ray).
//
// Default map: its own, preset kinect_v1 (pixel-native), of the camera fitted to the first organized cloud
// filtered (as the tools fit it: a principal point half a pixel off would put every point on its
// neighbour's ray, and the map would read as no data); until then, and when that cloud fits no pinhole
// camera (PCL_WARN), Kinect v1's nominal camera. setSensorPreset / setMapper give the camera instead.
//
// Each filter() with the map updated inserts its input again (PCL's filters are idempotent; this one
// integrates a stream): ask about one frame twice with setUpdateMap(false) the second time.
//
// Explicitly instantiated for PointXYZ, PointXYZI, PointXYZRGB, PointXYZRGBA and PointXYZL (for another
// type, pcl::copyPointCloud into one of them: only x, y, z are read).
#include "occ_improve/mapper.hpp"
#include "occ_improve/pcl/point_types.hpp"
#include "occ_improve/planning/point_selection.hpp"

#include <pcl/filters/filter_indices.h>

#include <cstddef>
#include <memory>
#include <vector>

namespace occ_improve {

enum class ImprovementSelection { range, top_count, top_fraction, contour };

template <typename PointT>
class ImprovementFilter : public pcl::FilterIndices<PointT> {
public:
  using Ptr = std::shared_ptr<ImprovementFilter<PointT>>;
  using ConstPtr = std::shared_ptr<const ImprovementFilter<PointT>>;

  explicit ImprovementFilter(bool extract_removed_indices = false);

  /// A map of its own for the preset (replaces any mapper set before).
  void setSensorPreset(const SensorPreset& preset, const GridOptions& grid_options = {});
  /// Shares a mapper with the caller (nullptr unsets it).
  void setMapper(std::shared_ptr<Mapper> mapper) {
    mapper_ = std::move(mapper);
    camera_assumed_ = false;
  }
  std::shared_ptr<Mapper> getMapper() const { return mapper_; }
  /// true (default): insert the input before selecting; false: select against the map as it is.
  void setUpdateMap(bool update) { update_map_ = update; }
  bool getUpdateMap() const { return update_map_; }
  void setInsertionOptions(const InsertionOptions& options) { insertion_options_ = options; }

  void setImprovementRange(float min_improvement, float max_improvement);
  void setTopCount(std::size_t count);
  void setTopFraction(double fraction);
  void setContourThreshold(float threshold = 0.0f);
  ImprovementSelection getSelection() const { return selection_; }

  /// Valid after filter(): see the header comment.
  const pcl::PointCloud<PointImprovement>& getImprovementCloud() const { return improvement_cloud_; }
  /// The insertion made by the last filter() call (zeros when the map was not updated).
  const MapperReport& getLastReport() const { return last_report_; }
  /// Points of the last filter() call's indices that had no ray.
  std::size_t getPointsWithoutRay() const { return points_without_ray_; }

protected:
  using pcl::FilterIndices<PointT>::filter_name_;
  using pcl::FilterIndices<PointT>::getClassName;
  using pcl::FilterIndices<PointT>::input_;
  using pcl::FilterIndices<PointT>::indices_;
  using pcl::FilterIndices<PointT>::negative_;
  using pcl::FilterIndices<PointT>::extract_removed_indices_;
  using pcl::FilterIndices<PointT>::removed_indices_;

  void applyFilter(pcl::Indices& indices) override;

private:
  /// Fills per-point improvement (NaN without a ray), the point's column (meaningful where the improvement
  /// is not NaN) and the improvement cloud; false on error.
  bool evaluate(std::vector<float>& point_improvement, std::vector<ColumnIndex>& point_column);
  /// The default map, before anything is inserted, takes the first organized cloud's fitted camera
  /// (PCL_WARN when it fits none: the nominal camera stays).
  void fitDefaultCamera();
  /// Indices (into input_) selected in normal mode, ascending.
  pcl::Indices select(const std::vector<float>& point_improvement, const std::vector<ColumnIndex>& point_column) const;
  pcl::Indices stratified_top(const pcl::Indices& with_ray, const std::vector<ColumnIndex>& point_column,
                              KeepAmount amount) const;
  bool parametersValid() const;

  std::shared_ptr<Mapper> mapper_;
  bool camera_assumed_ = true;  ///< the default map, of Kinect v1's nominal camera, before any organized cloud
  bool update_map_ = true;
  InsertionOptions insertion_options_;
  ImprovementSelection selection_ = ImprovementSelection::top_fraction;
  float min_improvement_ = 0.0f, max_improvement_ = 0.0f, contour_threshold_ = 0.0f;
  std::size_t top_count_ = 0;
  double top_fraction_ = 0.2;
  pcl::PointCloud<PointImprovement> improvement_cloud_;
  MapperReport last_report_;
  std::size_t points_without_ray_ = 0;
};

/// Inserts `frame` into `mapper`, then returns the indices (ascending) of the `fraction` of its points the
/// top modes keep (the frame itself is in the map by then: a thinned copy of what was inserted, for what
/// comes after the map; to thin what the map receives, choose before inserting, docs/PIPELINE.md).
/// Throws InvalidParameter for a fraction outside [0, 1], InvalidInput for a cloud the mapper refuses.
template <typename PointT>
pcl::Indices keep_most_improving(const pcl::PointCloud<PointT>& frame, const std::shared_ptr<Mapper>& mapper,
                                 double fraction);

}  // namespace occ_improve
