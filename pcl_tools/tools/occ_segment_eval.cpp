// occ_segment_eval: scores segmentations of labelled organized clouds (mOSD) against their ground truth,
// side by side: the negative-improvement segmentation (ours) and PCL's organized segmentation recipe.
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/segmentation_eval.hpp"
#include "occ_improve/pcl/cloud_segmentation.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/tool_options.hpp"

#include <pcl/common/io.h>
#include <pcl/console/parse.h>
#include <pcl/console/print.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace {

using namespace occ_improve;

void print_usage(const char* program) {
  std::printf(
      "Usage: %s <labelled.pcd> [more.pcd ...] [options]\n"
      "Scores segmentations of organized clouds with a ground-truth `label` field (mOSD: 0 invalid,\n"
      "1-9 table, 20+ objects): ours (negative-improvement contours, preset kinect_v1 from the cloud's\n"
      "intrinsics) and PCL's OrganizedMultiPlaneSegmentation + OrganizedConnectedComponentSegmentation\n"
      "with EuclideanClusterComparator, dominant plane left out in both unless said otherwise.\n"
      "  -no_plane                ours without dominant-plane removal\n"
      "  -preset NAME             ours: kinect_v1 (default), kinect_v1_spherical or kinect_v1_paper\n"
      "  -contour V               ours: contour rays have improvement < V (default -0.02)\n"
      "  -min_segment N           ours: smallest segment in rays (default 200)\n"
      "  -plane_distance D        ours: plane inlier band in m (default 0.006 pixel-native, 0.01 spherical)\n"
      "  -pcl_min_inliers N       PCL: OrganizedMultiPlaneSegmentation min inliers (default 3000)\n"
      "  -pcl_distance D          PCL: EuclideanClusterComparator threshold in m (default 0.005)\n"
      "  -pcl_min_cluster N       PCL: smallest cluster kept (default 500)\n"
      "  -h                       this help\n",
      program);
}

struct Totals {
  double f = 0, well = 0, boundary_precision = 0, boundary_recall = 0, ms = 0;
  std::size_t over = 0, under = 0, clouds = 0;
  void add(const SegmentationScore& s, double seconds) {
    f += s.mean_f;
    well += s.well_segmented_share;
    boundary_precision += s.boundary_precision;
    boundary_recall += s.boundary_recall;
    over += s.over_segmented;
    under += s.under_segmented;
    ms += 1e3 * seconds;
    ++clouds;
  }
};

void print_row(const std::string& name, const char* method, const SegmentationScore& s, double seconds) {
  std::printf("%-14s %-5s %6.3f %8.2f %5zu %6zu %7.3f %7.3f %9.1f\n", name.c_str(), method, s.mean_f,
              s.well_segmented_share, s.over_segmented, s.under_segmented, s.boundary_precision,
              s.boundary_recall, 1e3 * seconds);
}

void print_mean(const char* method, const Totals& t) {
  const double n = static_cast<double>(std::max<std::size_t>(t.clouds, 1));
  std::printf("%-14s %-5s %6.3f %8.2f %5zu %6zu %7.3f %7.3f %9.1f\n", "MEAN", method, t.f / n, t.well / n, t.over,
              t.under, t.boundary_precision / n, t.boundary_recall / n, t.ms / n);
}

// One labelled cloud: both segmentations scored, one row each.
void evaluate_cloud(const std::string& path, const std::string& preset_name, const SegmentationParams& ours,
                    const PclSegmentationParams& pcl_params, Totals& ours_total, Totals& pcl_total) {
  const InputScope scope(path);
  const std::string name = path.substr(path.find_last_of('/') + 1);
  const auto cloud = load_labelled_cloud(path);
  require_valid_points(span_of(cloud), path);
  if (ours_total.clouds == 0)  // the header only once a cloud has loaded, so an error stands alone
    std::printf("%-14s %-5s %6s %8s %5s %6s %7s %7s %9s\n", "cloud", "meth", "F", "F>=.75", "over", "under",
                "bnd P", "bnd R", "ms/frame");
  std::vector<std::uint32_t> truth(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) truth[i] = cloud[i].label;
  const int width = static_cast<int>(cloud.width), height = static_cast<int>(cloud.height);

  const auto our_result = segment_cloud(cloud, preset_by_name(preset_name, estimate_intrinsics(cloud)), ours);
  const auto our_score = evaluate_segmentation(truth, our_result.point_labels, width, height);
  print_row(name, "ours", our_score, our_result.total_seconds());
  ours_total.add(our_score, our_result.total_seconds());

  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::copyPointCloud(cloud, xyz);
  const auto pcl_result = pcl_organized_segmentation(xyz, pcl_params);
  const auto pcl_score = evaluate_segmentation(truth, pcl_result.labels, width, height);
  print_row(name, "pcl", pcl_score, pcl_result.total_seconds());
  pcl_total.add(pcl_score, pcl_result.total_seconds());
}

int run(int argc, char** argv) {
  if (argc < 2) {
    print_usage(argv[0]);
    return 1;
  }
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
  PclSegmentationParams pcl_params;
  pcl::console::parse_argument(argc, argv, "-pcl_min_inliers", pcl_params.min_plane_inliers);
  pcl::console::parse_argument(argc, argv, "-pcl_distance", pcl_params.cluster_distance_m);
  int min_cluster = static_cast<int>(pcl_params.min_cluster_points);
  pcl::console::parse_argument(argc, argv, "-pcl_min_cluster", min_cluster);
  pcl_params.min_cluster_points = static_cast<std::size_t>(std::max(1, min_cluster));
  std::string preset_name = "kinect_v1";
  pcl::console::parse_argument(argc, argv, "-preset", preset_name);
  SegmentationParams ours = segmentation_defaults(preset_by_name(preset_name));
  pcl::console::parse_argument(argc, argv, "-contour", ours.contour_improvement_below);
  int min_segment = static_cast<int>(ours.min_segment_columns);
  pcl::console::parse_argument(argc, argv, "-min_segment", min_segment);
  ours.min_segment_columns = static_cast<std::size_t>(std::max(1, min_segment));
  ours.remove_dominant_plane = !pcl::console::find_switch(argc, argv, "-no_plane");
  pcl::console::parse_argument(argc, argv, "-plane_distance", ours.plane_distance_m);
  ours.validate();
  pcl_params.validate();
  const std::vector<int> files = pcl::console::parse_file_extension_argument(argc, argv, ".pcd");
  if (files.empty()) throw InvalidParameter("no labelled .pcd file given (see -h)");

  std::printf("ours: %s dominant-plane removal; PCL: dominant plane left out\n",
              ours.remove_dominant_plane ? "with" : "without");
  Totals ours_total, pcl_total;
  try {
    for (int index : files) {
      throw_if_interrupted();
      evaluate_cloud(argv[index], preset_name, ours, pcl_params, ours_total, pcl_total);
    }
  } catch (const Interrupted&) {
    std::printf("interrupted after %zu of %zu clouds; means so far:\n", ours_total.clouds, files.size());
    print_mean("ours", ours_total);
    print_mean("pcl", pcl_total);
    throw;
  }
  print_mean("ours", ours_total);
  print_mean("pcl", pcl_total);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return occ_improve::run_tool(argc, argv, print_usage, run); }
