#include "occ_improve/eval/segmentation_eval.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/pcd_header.hpp"
#include "occ_improve/timing.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/features/integral_image_normal.h>
#include <pcl/segmentation/euclidean_cluster_comparator.h>
#include <pcl/segmentation/organized_connected_component_segmentation.h>
#include <pcl/segmentation/organized_multi_plane_segmentation.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <map>
#include <set>
#include <unordered_map>

namespace occ_improve {

using detail::require_parameter;

namespace {

bool has_field(const pcl::PCLPointCloud2& blob, const char* name) {
  return std::any_of(blob.fields.begin(), blob.fields.end(), [&](const pcl::PCLPointField& f) { return f.name == name; });
}

// Pixels on a boundary: a 4-neighbour with another label, both labelled (label != 0) and valid.
std::vector<std::uint8_t> boundary_mask(const std::vector<std::uint32_t>& labels, const std::vector<std::uint8_t>& valid,
                                        int width, int height) {
  std::vector<std::uint8_t> mask(labels.size(), 0);
  auto differs = [&](std::size_t a, std::size_t b) {
    return valid[a] && valid[b] && labels[a] != 0 && labels[b] != 0 && labels[a] != labels[b];
  };
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      if (u + 1 < width && differs(i, i + 1)) mask[i] = mask[i + 1] = 1;
      if (v + 1 < height && differs(i, i + width)) mask[i] = mask[i + width] = 1;
    }
  return mask;
}

// Pixels within `radius` (Chebyshev) of a set pixel: two separable running-window passes.
std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& mask, int width, int height, int radius) {
  std::vector<std::uint8_t> rows(mask.size(), 0), out(mask.size(), 0);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      if (!mask[i]) continue;
      for (int x = std::max(0, u - radius); x <= std::min(width - 1, u + radius); ++x)
        rows[static_cast<std::size_t>(v) * width + x] = 1;
    }
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      if (!rows[i]) continue;
      for (int y = std::max(0, v - radius); y <= std::min(height - 1, v + radius); ++y)
        out[static_cast<std::size_t>(y) * width + u] = 1;
    }
  return out;
}

// Share of the set pixels of `a` that lie in `b_dilated` and are labelled in `labelled` (1 when `a` is
// empty: nothing claimed, nothing wrong).
double matched_share(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b_dilated,
                     const std::vector<std::uint32_t>& labelled) {
  std::size_t total = 0, matched = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i]) {
      ++total;
      matched += b_dilated[i] && labelled[i] != 0;
    }
  return total == 0 ? 1.0 : static_cast<double>(matched) / static_cast<double>(total);
}

}  // namespace

pcl::PointCloud<pcl::PointXYZRGBL> load_labelled_cloud(const std::string& path) {
  pcl::PCLPointCloud2 blob;
  read_pcd_file(path, blob);
  for (const char* axis : {"x", "y", "z"}) require_pcd_field(blob, path, axis, pcl::PCLPointField::FLOAT32);
  if (!has_field(blob, "label"))
    throw FormatError("'" + path + "' has no 'label' field: ground-truth evaluation needs labelled points");
  require_pcd_field(blob, path, "label", pcl::PCLPointField::UINT32);
  if (blob.height <= 1)
    throw InvalidInput("'" + path + "' is not organized (height 1): the evaluation needs an organized cloud");
  pcl::PointCloud<pcl::PointXYZRGBL> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  return cloud;
}

void EvaluationOptions::validate() const {
  require_parameter(first_object_label >= 2, "first_object_label", first_object_label, ">= 2");
  require_parameter(well_segmented_f > 0 && well_segmented_f <= 1, "well_segmented_f", well_segmented_f, "in (0, 1]");
  require_parameter(fragment_share > 0 && fragment_share < 1, "fragment_share", fragment_share, "in (0, 1)");
  require_parameter(boundary_tolerance_px >= 0 && boundary_tolerance_px <= 50, "boundary_tolerance_px",
                    boundary_tolerance_px, "in [0, 50]");
}

SegmentationScore evaluate_segmentation(const std::vector<std::uint32_t>& ground_truth,
                                        const std::vector<std::uint32_t>& predicted, int width, int height,
                                        const EvaluationOptions& options) {
  options.validate();
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (width <= 0 || height <= 0 || ground_truth.size() != n || predicted.size() != n)
    throw InvalidInput("evaluate_segmentation: label images must both hold width x height labels");

  // Ground-truth regions: the table's parts count as one region (label 1), every object label as its own.
  auto region_of = [&](std::uint32_t gt) { return options.is_object_label(gt) ? gt : std::uint32_t{1}; };
  std::vector<std::uint8_t> valid(n);
  std::vector<std::uint32_t> regions(n);
  std::unordered_map<std::uint32_t, std::size_t> region_size, segment_size;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> overlap;  // (region, segment) -> points
  for (std::size_t i = 0; i < n; ++i) {
    valid[i] = ground_truth[i] != 0;
    if (!valid[i]) continue;
    regions[i] = region_of(ground_truth[i]);
    ++region_size[regions[i]];
    if (predicted[i] == 0) continue;
    ++segment_size[predicted[i]];
    ++overlap[{regions[i], predicted[i]}];
  }

  SegmentationScore score;
  score.segments = segment_size.size();
  std::map<std::uint32_t, std::vector<std::pair<std::uint32_t, std::size_t>>> by_region;  // region -> (segment, shared)
  std::map<std::uint32_t, std::vector<std::pair<std::uint32_t, std::size_t>>> by_segment;  // segment -> (region, shared)
  for (const auto& [key, shared] : overlap) {
    by_region[key.first].emplace_back(key.second, shared);
    by_segment[key.second].emplace_back(key.first, shared);
  }
  std::vector<std::uint32_t> object_labels;
  for (const auto& [region, size] : region_size)
    if (options.is_object_label(region)) object_labels.push_back(region);
  std::sort(object_labels.begin(), object_labels.end());

  for (std::uint32_t object : object_labels) {
    ObjectScore s;
    s.ground_truth_label = object;
    s.points = region_size[object];
    std::size_t best_shared = 0, fragments = 0;
    for (const auto& [segment, shared] : by_region[object]) {
      if (shared > best_shared) best_shared = shared, s.best_segment = segment;
      if (static_cast<double>(shared) >= options.fragment_share * static_cast<double>(s.points)) ++fragments;
    }
    s.over_segmented = fragments >= 2;
    if (s.best_segment != 0) {
      s.precision = static_cast<double>(best_shared) / static_cast<double>(segment_size[s.best_segment]);
      s.recall = static_cast<double>(best_shared) / static_cast<double>(s.points);
      s.f = 2 * s.precision * s.recall / (s.precision + s.recall);
      for (const auto& [other, shared] : by_segment[s.best_segment]) {
        if (other == object) continue;
        const double smaller = static_cast<double>(std::min(region_size[other], s.points));
        if (static_cast<double>(shared) >= options.fragment_share * smaller) s.under_segmented = true;
      }
    }
    score.mean_f += s.f;
    score.well_segmented_share += s.f >= options.well_segmented_f ? 1 : 0;
    score.over_segmented += s.over_segmented;
    score.under_segmented += s.under_segmented;
    score.objects.push_back(s);
  }
  if (!score.objects.empty()) {
    score.mean_f /= static_cast<double>(score.objects.size());
    score.well_segmented_share /= static_cast<double>(score.objects.size());
  }

  const auto truth_edges = boundary_mask(regions, valid, width, height);
  const auto predicted_edges = boundary_mask(predicted, valid, width, height);
  // Predicted edges are labelled by construction; a ground-truth edge left unlabelled is a miss.
  score.boundary_precision =
      matched_share(predicted_edges, dilate(truth_edges, width, height, options.boundary_tolerance_px), predicted);
  score.boundary_recall =
      matched_share(truth_edges, dilate(predicted_edges, width, height, options.boundary_tolerance_px), predicted);
  return score;
}

PooledScore pool_scores(const std::vector<SegmentationScore>& clouds, const EvaluationOptions& options) {
  options.validate();
  PooledScore pooled;
  for (const SegmentationScore& cloud : clouds)
    for (const ObjectScore& object : cloud.objects) {
      if (object.points < options.min_object_points) continue;
      ++pooled.objects;
      pooled.mean_f += object.f;
      pooled.well_segmented_share += object.f >= options.well_segmented_f ? 1 : 0;
    }
  if (pooled.objects > 0) {
    pooled.mean_f /= static_cast<double>(pooled.objects);
    pooled.well_segmented_share /= static_cast<double>(pooled.objects);
  }
  return pooled;
}

void PclSegmentationParams::validate() const {
  require_parameter(min_plane_inliers >= 3, "min_plane_inliers", min_plane_inliers, ">= 3");
  require_parameter(plane_angular_threshold_deg > 0 && plane_angular_threshold_deg < 90, "plane_angular_threshold_deg",
                    plane_angular_threshold_deg, "in (0, 90)");
  require_parameter(plane_distance_threshold_m > 0, "plane_distance_threshold_m", plane_distance_threshold_m, "> 0");
  require_parameter(cluster_distance_m > 0, "cluster_distance_m", cluster_distance_m, "> 0");
  require_parameter(min_cluster_points >= 1, "min_cluster_points", static_cast<double>(min_cluster_points), ">= 1");
  require_parameter(normal_max_depth_change_factor > 0, "normal_max_depth_change_factor",
                    normal_max_depth_change_factor, "> 0");
  require_parameter(normal_smoothing_size >= 1, "normal_smoothing_size", normal_smoothing_size, ">= 1");
}

PclSegmentationResult pcl_organized_segmentation(const pcl::PointCloud<pcl::PointXYZ>& cloud,
                                                 const PclSegmentationParams& params) {
  params.validate();
  if (!cloud.isOrganized() || cloud.height <= 1)
    throw InvalidInput("PCL's organized segmentation needs an organized cloud (height > 1)");
  using Clock = SteadyClock;
  PclSegmentationResult result;
  const auto input = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>(cloud);

  auto start = Clock::now();
  auto normals = std::make_shared<pcl::PointCloud<pcl::Normal>>();
  pcl::IntegralImageNormalEstimation<pcl::PointXYZ, pcl::Normal> normal_estimation;
  normal_estimation.setNormalEstimationMethod(normal_estimation.COVARIANCE_MATRIX);
  normal_estimation.setMaxDepthChangeFactor(params.normal_max_depth_change_factor);
  normal_estimation.setNormalSmoothingSize(params.normal_smoothing_size);
  normal_estimation.setInputCloud(input);
  normal_estimation.compute(*normals);
  result.normals_seconds = seconds_since(start);

  start = Clock::now();
  pcl::OrganizedMultiPlaneSegmentation<pcl::PointXYZ, pcl::Normal, pcl::Label> planes;
  planes.setMinInliers(params.min_plane_inliers);
  planes.setAngularThreshold(params.plane_angular_threshold_deg * M_PI / 180.0);
  planes.setDistanceThreshold(params.plane_distance_threshold_m);
  planes.setInputNormals(normals);
  planes.setInputCloud(input);
  std::vector<pcl::PlanarRegion<pcl::PointXYZ>, Eigen::aligned_allocator<pcl::PlanarRegion<pcl::PointXYZ>>> regions;
  std::vector<pcl::ModelCoefficients> coefficients;
  std::vector<pcl::PointIndices> inliers, label_indices, boundaries;
  auto plane_labels = std::make_shared<pcl::PointCloud<pcl::Label>>();
  planes.segmentAndRefine(regions, coefficients, inliers, plane_labels, label_indices, boundaries);
  result.planes = inliers.size();
  result.planes_seconds = seconds_since(start);

  start = Clock::now();
  result.labels.assign(cloud.size(), 0);
  std::uint32_t next_label = 1;
  // The dominant plane: the plane with most inliers; it becomes one segment of its own.
  std::uint32_t dominant_plane_label = std::numeric_limits<std::uint32_t>::max();
  if (params.remove_dominant_plane && !inliers.empty()) {
    const auto largest = std::max_element(inliers.begin(), inliers.end(), [](const auto& a, const auto& b) {
      return a.indices.size() < b.indices.size();
    });
    if (!largest->indices.empty()) {
      dominant_plane_label = (*plane_labels)[static_cast<std::size_t>(largest->indices.front())].label;
      for (int i : largest->indices) result.labels[static_cast<std::size_t>(i)] = next_label;
      ++next_label;
    }
  }
  // PCL 1.13's EuclideanClusterComparator joins only points whose plane labels ARE in the "exclude" set
  // (ENVIRONMENT.md): pass every label except the dominant plane's.
  auto joinable = std::make_shared<std::set<std::uint32_t>>();
  for (const auto& l : *plane_labels)
    if (l.label != dominant_plane_label) joinable->insert(l.label);
  auto comparator = std::make_shared<pcl::EuclideanClusterComparator<pcl::PointXYZ, pcl::Label>>();
  comparator->setInputCloud(input);
  comparator->setLabels(plane_labels);
  comparator->setExcludeLabels(joinable);
  comparator->setDistanceThreshold(params.cluster_distance_m, false);
  pcl::PointCloud<pcl::Label> cluster_labels;
  std::vector<pcl::PointIndices> clusters;
  pcl::OrganizedConnectedComponentSegmentation<pcl::PointXYZ, pcl::Label> components(comparator);
  components.setInputCloud(input);
  components.segment(cluster_labels, clusters);
  for (const auto& cluster : clusters) {
    if (cluster.indices.size() < params.min_cluster_points) continue;
    for (int i : cluster.indices)
      if (result.labels[static_cast<std::size_t>(i)] == 0) result.labels[static_cast<std::size_t>(i)] = next_label;
    ++next_label;
    ++result.clusters;
  }
  result.clusters_seconds = seconds_since(start);
  return result;
}

}  // namespace occ_improve
