// occ_segment_eval: scores segmentations of labelled organized clouds (mOSD) against their ground truth,
// side by side: the negative-improvement segmentation (ours) and PCL's organized segmentation recipe.
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/segmentation_eval.hpp"
#include "occ_improve/pcl/cloud_segmentation.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/progress.hpp"
#include "occ_improve/tools/segmentation_flags.hpp"
#include "occ_improve/tools/tool_main.hpp"

#include <pcl/common/io.h>
#include <pcl/console/print.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace {

using namespace occ_improve;

const ToolFlags kFlags{
    "occ_segment_eval",
    {"LABELLED.pcd... [options]"},
    "Scores segmentations of organized clouds with a ground-truth `label` field (mOSD: 0 invalid, 1-9\n"
    "table, 20+ objects): ours (negative-improvement contours, intrinsics fitted to the cloud) and PCL's\n"
    "OrganizedMultiPlaneSegmentation + OrganizedConnectedComponentSegmentation with\n"
    "EuclideanClusterComparator, the dominant plane left out in both unless -no_plane.\n",
    {"-q", "-preset", "-contour", "-min_segment", "-no_plane", "-no_crease", "-plane_distance", "-pcl_min_inliers", "-pcl_distance",
     "-pcl_min_cluster"},
    {},
    {},
    "  LABELLED.pcd              organized PCD with x y z and a uint32 `label` field\n"};

// Per method: each cloud's score and times, for the mean of per-cloud means and the pooled objects.
struct MethodRuns {
  std::vector<SegmentationScore> scores;
  double segmentation_ms = 0, total_ms = 0;
  void add(const SegmentationScore& s, double segmentation_seconds, double total_seconds) {
    scores.push_back(s);
    segmentation_ms += 1e3 * segmentation_seconds;
    total_ms += 1e3 * total_seconds;
  }
};

void print_header() {
  std::printf("%-14s %-5s %6s %8s %5s %6s %7s %7s %7s %9s\n", "cloud", "meth", "F", "F>=.75", "over", "under",
              "bnd P", "bnd R", "seg ms", "ms/frame");
}

void print_row(const std::string& name, const char* method, const SegmentationScore& s, double segmentation_seconds,
               double total_seconds) {
  std::printf("%-14s %-5s %6.3f %8.2f %5zu %6zu %7.3f %7.3f %7.1f %9.1f\n", name.c_str(), method, s.mean_f,
              s.well_segmented_share, s.over_segmented, s.under_segmented, s.boundary_precision,
              s.boundary_recall, 1e3 * segmentation_seconds, 1e3 * total_seconds);
}

// MEAN: today's mean of per-cloud means (every object of a cloud, each cloud weighing the same); the over-
// and under-segmented objects, counts, are summed.
void print_mean(const char* method, const MethodRuns& runs) {
  SegmentationScore mean;
  for (const SegmentationScore& s : runs.scores) {
    mean.mean_f += s.mean_f;
    mean.well_segmented_share += s.well_segmented_share;
    mean.over_segmented += s.over_segmented;
    mean.under_segmented += s.under_segmented;
    mean.boundary_precision += s.boundary_precision;
    mean.boundary_recall += s.boundary_recall;
  }
  const double n = static_cast<double>(std::max<std::size_t>(runs.scores.size(), 1));
  mean.mean_f /= n;
  mean.well_segmented_share /= n;
  mean.boundary_precision /= n;
  mean.boundary_recall /= n;
  print_row("MEAN", method, mean, runs.segmentation_ms / n / 1e3, runs.total_ms / n / 1e3);
}

// POOLED: every ground-truth object of at least EvaluationOptions::min_object_points points, all clouds.
void print_pooled(const char* method, const MethodRuns& runs) {
  const EvaluationOptions options;
  const PooledScore pooled = pool_scores(runs.scores, options);
  std::printf("%-14s %-5s %6.3f %8.2f %7zu   (objects of >= %zu points, all clouds)\n", "POOLED", method,
              pooled.mean_f, pooled.well_segmented_share, pooled.objects, options.min_object_points);
}

void print_summary(const MethodRuns& ours, const MethodRuns& pcl) {
  print_mean("ours", ours);
  print_mean("pcl", pcl);
  std::printf("%-14s %-5s %6s %8s %7s\n", "", "meth", "F", "F>=.75", "objects");
  print_pooled("ours", ours);
  print_pooled("pcl", pcl);
}

// One labelled cloud: both segmentations scored, one row each.
void evaluate_cloud(const std::string& path, const std::string& preset_name, const SegmentationParams& ours,
                    const PclSegmentationParams& pcl_params, MethodRuns& ours_runs, MethodRuns& pcl_runs,
                    ProgressLine& progress) {
  const InputScope scope(path);
  const std::string name = path.substr(path.find_last_of('/') + 1);
  const auto cloud = load_labelled_cloud(path);
  require_valid_points(span_of(cloud), path);
  require_points_in_metres(span_of(cloud), path, preset_by_name(preset_name).geometry, "cloud",
                           ": the tools read clouds in metres");
  std::vector<std::uint32_t> truth(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) truth[i] = cloud[i].label;
  // A cloud without a ground-truth object scored F = 0 and weighed in the means as a failure of both methods.
  const EvaluationOptions evaluation;  // the scores' (evaluate_segmentation's defaults)
  if (std::none_of(truth.begin(), truth.end(), [&](std::uint32_t label) { return evaluation.is_object_label(label); }))
    throw InvalidInput("no ground-truth object in it (every label is below " +
                       std::to_string(evaluation.first_object_label) + ", the table's or none): nothing to score");
  progress.finish();  // the rows below start on a clean line
  if (ours_runs.scores.empty()) print_header();  // only once a cloud has loaded, so an error stands alone
  const int width = static_cast<int>(cloud.width), height = static_cast<int>(cloud.height);

  const auto our_result = segment_cloud(cloud, preset_by_name(preset_name, estimate_intrinsics(cloud)), ours);
  const auto our_score = evaluate_segmentation(truth, our_result.point_labels, width, height);
  print_row(name, "ours", our_score, our_result.segmentation_seconds, our_result.total_seconds());
  ours_runs.add(our_score, our_result.segmentation_seconds, our_result.total_seconds());

  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::copyPointCloud(cloud, xyz);
  const auto pcl_result = pcl_organized_segmentation(xyz, pcl_params);
  const auto pcl_score = evaluate_segmentation(truth, pcl_result.labels, width, height);
  // PCL's recipe is segmentation from the cloud as a whole: its own share is all of it.
  print_row(name, "pcl", pcl_score, pcl_result.total_seconds(), pcl_result.total_seconds());
  pcl_runs.add(pcl_score, pcl_result.total_seconds(), pcl_result.total_seconds());
}

int run(const CommandLine& command_line) {
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
  PclSegmentationParams pcl_params;
  pcl_params.min_plane_inliers = static_cast<unsigned>(*command_line.integer("-pcl_min_inliers"));
  pcl_params.cluster_distance_m = static_cast<float>(*command_line.number("-pcl_distance"));
  pcl_params.min_cluster_points = static_cast<std::size_t>(*command_line.integer("-pcl_min_cluster"));
  const std::string preset_name = *command_line.text("-preset");
  SegmentationParams ours = segmentation_defaults(preset_by_name(preset_name));
  apply_segmentation_flags(command_line, ours);
  pcl_params.validate();
  const std::vector<std::string>& files = command_line.positionals();
  if (files.empty()) throw InvalidParameter("no labelled .pcd file given (see -h)");

  std::printf("ours: %s dominant-plane removal, %s concave creases; PCL: dominant plane left out\n",
              ours.remove_dominant_plane ? "with" : "without", ours.split_concave_creases ? "with" : "without");
  MethodRuns ours_runs, pcl_runs;
  ProgressLine progress(command_line, "cloud");
  try {
    for (const std::string& file : files) {
      throw_if_stop_requested();
      evaluate_cloud(file, preset_name, ours, pcl_params, ours_runs, pcl_runs, progress);
      progress.update(ours_runs.scores.size(), files.size());
    }
    progress.finish();
  } catch (const Cancelled&) {
    progress.finish();
    std::printf("interrupted after %zu of %zu clouds; means so far:\n", ours_runs.scores.size(), files.size());
    print_summary(ours_runs, pcl_runs);
    throw;
  }
  print_summary(ours_runs, pcl_runs);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return occ_improve::run_tool(argc, argv, kFlags, run); }
