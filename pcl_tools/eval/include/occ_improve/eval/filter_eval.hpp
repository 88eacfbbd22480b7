#pragma once
// The selective-acquisition question in a PCL pipeline (docs/SELECTIVE.md, "The same question in a PCL
// pipeline"): per frame of a posed sequence, keep a fraction of the points by ImprovementFilter (chosen
// against the map before the frame is inserted), by pcl::RandomSample or by pcl::VoxelGrid keeping about
// the same number, insert what is kept, and score the map against the map from all points
// (depth_agreement: predicted depth within 2 sigma(z) of the reference surface).
#include "occ_improve/mapper.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve {

using FrameCloud = pcl::PointCloud<pcl::PointXYZ>;
using Frames = std::vector<FrameCloud::ConstPtr>;

/// improvement_shuffled: ImprovementFilter on the frame's points in a seeded random order. The filter
/// breaks ties by point index, and on rays it knows nothing about every point ties (no-data improvement),
/// so in image order it keeps the top rows; the shuffled order measures what that tie-break costs.
enum class KeepStrategy { improvement, improvement_shuffled, random_sample, voxel_grid };
/// "improvement", "improvement_shuffled", "random_sample", "voxel_grid" (the CSV's names).
const char* keep_strategy_name(KeepStrategy strategy);

/// The first `max_frames` frames (0: all) of a posed sequence as DepthSequenceGrabber emits them (in the
/// first frame's view), each reduced to its points that have a column in `geometry`, so that every
/// strategy chooses among the same points. Throws InvalidInput when the sequence has no poses (one view
/// needs them) or a frame cannot be read.
Frames read_posed_frames(DepthSequence sequence, const PinholeIntrinsics& intrinsics, const GridGeometry& geometry,
                         std::size_t max_frames);

/// pcl::VoxelGrid with the leaf size in [smallest without index overflow, 1 m], found by bisection, whose
/// output is closest to `count` points (within 0.5 % stops the search). Empty for an empty frame or count 0.
struct VoxelKeep {
  FrameCloud cloud;
  float leaf_m = 0;
};
VoxelKeep voxel_grid_keeping(const FrameCloud::ConstPtr& frame, std::size_t count);

struct FilterEvalOptions {
  int radius_columns = 16;  ///< predict_depth radius
  std::uint32_t seed = 1;   ///< RandomSample's and the shuffle's seed (plus the frame number)
};

/// One frame of one run.
struct FilterStep {
  std::size_t frame = 0;
  std::size_t asked = 0;   ///< round(fraction x the frame's points)
  std::size_t kept = 0;    ///< what the strategy kept of this frame
  std::size_t points = 0;  ///< kept so far, this frame included
  std::size_t columns = 0; ///< distinct columns (rays) this frame's kept points fall in: how spread they are
  float leaf_m = 0;        ///< voxel_grid only
  double quality = 0;      ///< depth_agreement share against the reference
};

/// The map from every point of every frame.
Mapper map_of_all_points(const Frames& frames, const SensorPreset& preset);

/// `map`'s agreement with `reference` (depth_agreement at 2 sigma, `reference`'s sensor model).
double quality_against(const Mapper& map, const Mapper& reference, int radius_columns);

/// One strategy keeping `fraction` of each frame, from an empty map of `preset`. Throws InvalidParameter
/// for a fraction outside (0, 1].
std::vector<FilterStep> run_keep_strategy(KeepStrategy strategy, double fraction, const Frames& frames,
                                          const SensorPreset& preset, const Mapper& reference,
                                          const FilterEvalOptions& options = {});

}  // namespace occ_improve
