#include "occ_improve/eval/filter_eval.hpp"

#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/improvement_filter.hpp"

#include <pcl/common/common.h>
#include <pcl/filters/random_sample.h>
#include <pcl/filters/voxel_grid.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <random>
#include <string>

namespace occ_improve {

const char* keep_strategy_name(KeepStrategy strategy) {
  switch (strategy) {
    case KeepStrategy::improvement: return "improvement";
    case KeepStrategy::improvement_shuffled: return "improvement_shuffled";
    case KeepStrategy::random_sample: return "random_sample";
    case KeepStrategy::voxel_grid: return "voxel_grid";
  }
  return "?";
}

namespace {

FrameCloud::Ptr points_with_a_column(const FrameCloud& cloud, const GridGeometry& geometry) {
  FrameCloud::Ptr kept(new FrameCloud);
  ColumnIndex column;
  for (const auto& p : cloud.points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && geometry.column_of(p.x, p.y, p.z, column))
      kept->push_back(p);
  return kept;
}

}  // namespace

Frames read_posed_frames(DepthSequence sequence, const PinholeIntrinsics& intrinsics, const GridGeometry& geometry,
                         std::size_t max_frames) {
  if (max_frames > 0 && sequence.frames.size() > max_frames) sequence.frames.resize(max_frames);
  DepthSequenceGrabber grabber(std::move(sequence), intrinsics);
  if (!grabber.posesApplied())
    throw InvalidInput("the sequence has no poses (7-Scenes' *.pose.txt, TUM's groundtruth.txt): its frames cannot be "
                       "put in one view");
  Frames frames;
  std::string failure;
  std::mutex mutex;  // the callbacks run on the grabber's thread
  std::function<void(const FrameCloud::ConstPtr&)> keep = [&](const FrameCloud::ConstPtr& cloud) {
    FrameCloud::Ptr reduced = points_with_a_column(*cloud, geometry);
    std::lock_guard<std::mutex> lock(mutex);
    frames.push_back(std::move(reduced));
  };
  grabber.registerCallback(keep);
  grabber.setErrorCallback([&](const std::string& message) {
    std::lock_guard<std::mutex> lock(mutex);
    if (failure.empty()) failure = message;
  });
  grabber.start();
  grabber.waitUntilDone();
  grabber.stop();
  // A skipped frame would shift every later frame's number and leave a hole in the reference.
  if (!failure.empty()) throw InvalidInput(failure);
  return frames;
}

namespace {

std::size_t voxel_count(const FrameCloud::ConstPtr& frame, float leaf, FrameCloud& out) {
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(frame);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(out);
  return out.size();
}

}  // namespace

VoxelKeep voxel_grid_keeping(const FrameCloud::ConstPtr& frame, std::size_t count) {
  if (frame->empty() || count == 0) return {};  // getMinMax3D has no extent to give for an empty cloud
  pcl::PointXYZ min_p, max_p;
  pcl::getMinMax3D(*frame, min_p, max_p);
  const double volume = std::max(1e-9, double(max_p.x - min_p.x) * (max_p.y - min_p.y) * (max_p.z - min_p.z));
  // Below this leaf VoxelGrid's voxel index overflows 32 bits and it returns the input unfiltered.
  float low = static_cast<float>(std::max(1e-3, 1.01 * std::cbrt(volume / 2147483647.0)));
  float high = 1.0f;
  VoxelKeep best;
  std::size_t best_error = static_cast<std::size_t>(-1);
  FrameCloud trial;
  // The output shrinks as the leaf grows; bisect in log(leaf), 20 steps reach 1e-6 of the log range.
  for (int step = 0; step < 20 && best_error > count / 200; ++step) {
    const float leaf = std::sqrt(low * high);
    const std::size_t kept = voxel_count(frame, leaf, trial);
    const std::size_t error = kept > count ? kept - count : count - kept;
    if (error < best_error) {
      best_error = error;
      best.cloud.swap(trial);
      best.leaf_m = leaf;
    }
    (kept > count ? low : high) = leaf;
  }
  return best;
}

Mapper map_of_all_points(const Frames& frames, const SensorPreset& preset) {
  Mapper mapper(preset);
  for (const auto& frame : frames) mapper.insert(span_of(*frame));
  return mapper;
}

double quality_against(const Mapper& map, const Mapper& reference, int radius_columns) {
  DepthPredictionParams params;
  params.radius_columns = radius_columns;
  return depth_agreement(reference.surface(), predict_depth(map.surface(), params), reference.model()).share();
}

namespace {

FrameCloud::ConstPtr shuffled(const FrameCloud& frame, std::uint32_t seed) {
  FrameCloud::Ptr out(new FrameCloud(frame));
  std::mt19937 random(seed);
  std::shuffle(out->points.begin(), out->points.end(), random);
  return out;
}

std::size_t distinct_columns(const FrameCloud& cloud, const GridGeometry& geometry) {
  std::vector<ColumnIndex> columns;
  columns.reserve(cloud.size());
  ColumnIndex column;
  for (const auto& p : cloud.points)
    if (geometry.column_of(p.x, p.y, p.z, column)) columns.push_back(column);
  std::sort(columns.begin(), columns.end());
  return static_cast<std::size_t>(std::unique(columns.begin(), columns.end()) - columns.begin());
}

/// The points `strategy` keeps of `frame` (about `count`), chosen against `mapper` as it is.
FrameCloud keep_points(KeepStrategy strategy, const FrameCloud::ConstPtr& frame, std::size_t count, double fraction,
                       const std::shared_ptr<Mapper>& mapper, std::uint32_t seed, float& leaf_m) {
  FrameCloud kept;
  if (strategy == KeepStrategy::improvement || strategy == KeepStrategy::improvement_shuffled) {
    ImprovementFilter<pcl::PointXYZ> filter;
    filter.setMapper(mapper);
    filter.setUpdateMap(false);  // choose before the frame is inserted; run_keep_strategy inserts what is kept
    filter.setTopFraction(fraction);
    filter.setInputCloud(strategy == KeepStrategy::improvement ? frame : shuffled(*frame, seed));
    filter.filter(kept);
  } else if (strategy == KeepStrategy::random_sample) {
    pcl::RandomSample<pcl::PointXYZ> sample;
    sample.setInputCloud(frame);
    sample.setSample(static_cast<unsigned int>(count));
    sample.setSeed(seed);
    sample.filter(kept);
  } else {
    VoxelKeep voxel = voxel_grid_keeping(frame, count);
    leaf_m = voxel.leaf_m;
    kept.swap(voxel.cloud);
  }
  return kept;
}

}  // namespace

std::vector<FilterStep> run_keep_strategy(KeepStrategy strategy, double fraction, const Frames& frames,
                                          const SensorPreset& preset,
                                          const Mapper& reference, const FilterEvalOptions& options) {
  detail::require_parameter(fraction > 0 && fraction <= 1, "fraction", fraction, "in (0, 1]");
  auto mapper = std::make_shared<Mapper>(preset);
  std::vector<FilterStep> steps;
  std::size_t points = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    FilterStep step;
    step.frame = i;
    step.asked = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(frames[i]->size())));
    const FrameCloud kept = keep_points(strategy, frames[i], step.asked, fraction, mapper,
                                        options.seed + static_cast<std::uint32_t>(i), step.leaf_m);
    if (!kept.empty()) mapper->insert(span_of(kept));
    step.kept = kept.size();
    step.columns = distinct_columns(kept, mapper->geometry());
    step.points = points += kept.size();
    step.quality = quality_against(*mapper, reference, options.radius_columns);
    steps.push_back(step);
  }
  return steps;
}

}  // namespace occ_improve
