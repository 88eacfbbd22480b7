// Selective sensing with the ImprovementFilter: a map already holds a first view; of the next frame,
// keep only the share of points that improves the map most (here 20 %), so a pipeline cuts the data
// where it adds least. Then the negative-improvement contours (depth discontinuities) of the frame.
//
// Usage: example_pcl_filter [FIRST.pcd SECOND.pcd [KEPT.pcd]]
//   without arguments: two noisy frames of the built-in sample scene, paper preset;
//   with PCDs: two organized Kinect frames from the same viewpoint, kinect_v1 preset.
#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/pcl/improvement_filter.hpp"
#include "occ_improve/sample_scene.hpp"

#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>

#include <cmath>
#include <cstdio>

namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Cloud::Ptr sample_frame(std::uint32_t seed) {
  occ_improve::sample::SceneOptions options;
  options.seed = seed;
  const auto frame = occ_improve::sample::generate_scene(options);
  return Cloud::Ptr(
      new Cloud(occ_improve::organized_cloud(frame.points(), frame.intrinsics.width, frame.intrinsics.height)));
}

double mean_improvement(const pcl::PointCloud<occ_improve::PointImprovement>& fields, const pcl::Indices& indices) {
  double sum = 0;
  std::size_t n = 0;
  for (const auto i : indices)
    if (std::isfinite(fields[i].improvement)) {
      sum += fields[i].improvement;
      ++n;
    }
  return n ? sum / static_cast<double>(n) : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const bool from_files = argc >= 3;
    const Cloud::Ptr first = from_files ? Cloud::Ptr(new Cloud(occ_improve::load_pcd_frame(argv[1]).cloud)) : sample_frame(1);
    const Cloud::Ptr second = from_files ? Cloud::Ptr(new Cloud(occ_improve::load_pcd_frame(argv[2]).cloud)) : sample_frame(2);
    // A file's camera is fitted to its organized points (as the tools do): never assumed.
    auto mapper = std::make_shared<occ_improve::Mapper>(
        from_files ? occ_improve::kinect_v1(occ_improve::estimate_intrinsics(*first)) : occ_improve::kinect_v1_paper());
    mapper->insert(occ_improve::span_of(*first));

    // Insert the second frame and keep 20 % of it, chosen by the map (ImprovementFilter's top modes).
    occ_improve::ImprovementFilter<pcl::PointXYZ> filter(true);
    filter.setMapper(mapper);
    filter.setInputCloud(second);
    filter.setTopFraction(0.2);
    pcl::Indices kept;
    filter.filter(kept);
    const pcl::Indices& removed = *filter.getRemovedIndices();
    const auto& fields = filter.getImprovementCloud();  // improvement, probability, depth per point
    std::printf("frame of %zu points, %zu without a ray (no return / outside the field of view)\n", second->size(),
                filter.getPointsWithoutRay());
    std::printf("kept %zu points (20%% of those with a ray), mean improvement %.4f; removed %zu, mean %.4f\n",
                kept.size(), mean_improvement(fields, kept), removed.size(), mean_improvement(fields, removed));

    // Depth discontinuities: rays where one more measurement would lower the surface probability.
    occ_improve::ImprovementFilter<pcl::PointXYZ> contours;
    contours.setMapper(mapper);
    contours.setUpdateMap(false);  // the frame is already in the map
    contours.setInputCloud(second);
    contours.setContourThreshold(0.0f);
    pcl::Indices on_contours;
    contours.filter(on_contours);
    std::printf("%zu points lie on negative-improvement contours\n", on_contours.size());

    if (argc >= 4) {
      Cloud kept_cloud;
      pcl::copyPointCloud(*second, kept, kept_cloud);
      if (pcl::io::savePCDFileBinary(argv[3], kept_cloud) != 0) throw occ_improve::IoError(std::string("cannot write ") + argv[3]);
      std::printf("wrote %s\n", argv[3]);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
