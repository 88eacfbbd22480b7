#pragma once
// Measuring a segmentation of an organized cloud against ground-truth labels (the mOSD convention:
// 0 invalid, 1-9 table, 20+ one label per connected object part), and PCL's own organized
// segmentation as the baseline to compare with.
//
// Scores (per ground-truth object, i.e. per label >= first_object_label):
//  - the best-overlapping segment is the one sharing the most valid points with the object;
//    precision = shared / segment size, recall = shared / object size, F = their harmonic mean;
//  - over-segmented: at least two segments each hold >= fragment_share of the object's points;
//  - under-segmented: the object's best segment also holds >= fragment_share of the points of another
//    ground-truth region (another object, or the table taken as one region), counted relative to the
//    smaller of the two regions, so a merge into the much larger table counts too;
//  - boundary precision / recall: boundary pixels (a 4-neighbour with another label, both valid) of the
//    prediction within boundary_tolerance_px (Chebyshev) of a ground-truth boundary pixel, and back. Like for
//    like between methods: a ground-truth boundary pixel the method leaves unlabelled is a miss, even when a
//    predicted boundary lies within the tolerance (a method that leaves edges unlabelled gains nothing);
//  - pooled over clouds (pool_scores): the mean F over all objects of at least min_object_points points and
//    the share of them at F >= well_segmented_f, so every object weighs the same whatever its cloud holds.
// Only points valid in the ground truth (label != 0) count; a predicted label 0 means "no segment".

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

/// An organized labelled cloud: x y z and the ground-truth label in `label`.
/// Throws IoError (unreadable), FormatError (no x/y/z or no `label` field), InvalidInput (not organized).
pcl::PointCloud<pcl::PointXYZRGBL> load_labelled_cloud(const std::string& path);

struct EvaluationOptions {
  std::uint32_t first_object_label = 20;  ///< labels in [1, first_object_label) are the table
  double well_segmented_f = 0.75;         ///< an object counts as well segmented from this F on
  double fragment_share = 0.10;           ///< over/under-segmentation threshold (share of a region)
  int boundary_tolerance_px = 2;
  std::size_t min_object_points = 100;    ///< smaller ground-truth objects are left out of the pooled scores
  void validate() const;
  /// Whether a ground-truth label names an object (0 is no label, below first_object_label the table).
  bool is_object_label(std::uint32_t label) const { return label >= first_object_label; }
};

struct ObjectScore {
  std::uint32_t ground_truth_label = 0;
  std::size_t points = 0;
  std::uint32_t best_segment = 0;  ///< 0 when no segment overlaps the object
  double precision = 0, recall = 0, f = 0;
  bool over_segmented = false, under_segmented = false;
};

struct SegmentationScore {
  std::vector<ObjectScore> objects;
  double mean_f = 0;                ///< over objects (0 when there are none)
  double well_segmented_share = 0;  ///< share of objects with F >= well_segmented_f
  std::size_t over_segmented = 0, under_segmented = 0;
  double boundary_precision = 0, boundary_recall = 0;
  std::size_t segments = 0;  ///< distinct predicted labels on ground-truth-valid points
};

/// Both label images are row-major width x height. Throws InvalidInput on size mismatch.
SegmentationScore evaluate_segmentation(const std::vector<std::uint32_t>& ground_truth,
                                        const std::vector<std::uint32_t>& predicted, int width, int height,
                                        const EvaluationOptions& options = {});

/// Objects of all clouds pooled: every ground-truth object of at least options.min_object_points points.
struct PooledScore {
  std::size_t objects = 0;
  double mean_f = 0;                ///< 0 when there are no objects
  double well_segmented_share = 0;  ///< share of objects with F >= options.well_segmented_f
};
PooledScore pool_scores(const std::vector<SegmentationScore>& clouds, const EvaluationOptions& options = {});

/// PCL's organized segmentation recipe (pcl/apps organized_segmentation_demo): integral-image normals,
/// OrganizedMultiPlaneSegmentation, then OrganizedConnectedComponentSegmentation with an
/// EuclideanClusterComparator over the points that are not in the dominant plane.
struct PclSegmentationParams {
  unsigned min_plane_inliers = 3000;
  double plane_angular_threshold_deg = 3.0;
  double plane_distance_threshold_m = 0.02;
  float cluster_distance_m = 0.005f;  ///< EuclideanClusterComparator threshold between neighbours
  std::size_t min_cluster_points = 500;
  float normal_max_depth_change_factor = 0.02f;
  float normal_smoothing_size = 20.0f;
  bool remove_dominant_plane = true;  ///< leave the largest plane out of the clustering
  void validate() const;
};

struct PclSegmentationResult {
  std::vector<std::uint32_t> labels;  ///< per point; 0 = no segment; the dominant plane is one segment
  std::size_t planes = 0, clusters = 0;
  double normals_seconds = 0, planes_seconds = 0, clusters_seconds = 0;
  double total_seconds() const { return normals_seconds + planes_seconds + clusters_seconds; }
};

/// Throws InvalidInput when the cloud is not organized, InvalidParameter for bad params.
PclSegmentationResult pcl_organized_segmentation(const pcl::PointCloud<pcl::PointXYZ>& cloud,
                                                 const PclSegmentationParams& params = {});

}  // namespace occ_improve
