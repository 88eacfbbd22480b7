// The segmentation on real labelled clouds (mOSD) against ground truth and against PCL's recipe.
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/segmentation_eval.hpp"
#include "occ_improve/pcl/cloud_segmentation.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "support/test_data.hpp"

#include <gtest/gtest.h>
#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>

#include <cstdio>
#include <filesystem>

namespace occ_improve {
namespace {

const char* const kClouds[] = {"learn0", "learn8", "learn16", "learn17", "learn22",
                               "learn25", "learn30", "learn33", "learn40", "learn44"};

TEST(SegmentationEval, OursScoresAtLeastPclOnMosd) {
  OCC_REQUIRE_DATA(first, "segmentation/mosd_learn/learn0.pcd");
  SegmentationParams ours = segmentation_defaults(kinect_v1());
  ours.remove_dominant_plane = true;
  double ours_f = 0, pcl_f = 0;
  for (const char* name : kClouds) {
    const std::string path = test::data_file(std::string("segmentation/mosd_learn/") + name + ".pcd");
    ASSERT_FALSE(path.empty()) << name;
    const auto cloud = load_labelled_cloud(path);
    std::vector<std::uint32_t> truth(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) truth[i] = cloud[i].label;
    const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
    const auto result = segment_cloud(cloud, kinect_v1(estimate_intrinsics(cloud)), ours);
    ours_f += evaluate_segmentation(truth, result.point_labels, w, h).mean_f;
    pcl::PointCloud<pcl::PointXYZ> xyz;
    pcl::copyPointCloud(cloud, xyz);
    pcl_f += evaluate_segmentation(truth, pcl_organized_segmentation(xyz).labels, w, h).mean_f;
  }
  ours_f /= std::size(kClouds);
  pcl_f /= std::size(kClouds);
  std::printf("mean F over %zu mOSD clouds: ours %.3f, PCL %.3f\n", std::size(kClouds), ours_f, pcl_f);
  EXPECT_GE(ours_f, 0.78);  // measured 0.825
  EXPECT_GE(ours_f, pcl_f - 0.01);
}

TEST(SegmentationEval, PerfectLabellingScoresOne) {
  const int w = 8, h = 4;
  std::vector<std::uint32_t> truth(w * h, 0);
  for (int i = 0; i < w * h; ++i) truth[static_cast<std::size_t>(i)] = (i % w) < 4 ? 20 : 21;
  std::vector<std::uint32_t> predicted(truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i) predicted[i] = truth[i] == 20 ? 7 : 9;  // any label names
  const SegmentationScore s = evaluate_segmentation(truth, predicted, w, h);
  EXPECT_DOUBLE_EQ(s.mean_f, 1.0);
  EXPECT_EQ(s.over_segmented + s.under_segmented, 0u);
  std::vector<std::uint32_t> merged(truth.size(), 1);  // one segment for both objects
  EXPECT_LT(evaluate_segmentation(truth, merged, w, h).mean_f, 0.8);
  EXPECT_THROW(evaluate_segmentation(truth, std::vector<std::uint32_t>(3, 1), w, h), InvalidInput);
}

TEST(SegmentationEval, BadInputIsRefusedClearly) {
  const auto dir = std::filesystem::temp_directory_path() / "occ_seg_eval_test";
  std::filesystem::create_directories(dir);
  pcl::PointCloud<pcl::PointXYZ> unlabelled;
  unlabelled.width = 4;
  unlabelled.height = 2;
  unlabelled.resize(8, pcl::PointXYZ(0.1f, 0.1f, 1.0f));
  const std::string path = (dir / "no_label.pcd").string();
  ASSERT_EQ(pcl::io::savePCDFileASCII(path, unlabelled), 0);
  EXPECT_THROW(load_labelled_cloud(path), FormatError);
  pcl::PointCloud<pcl::PointXYZ> flat;
  flat.resize(100, pcl::PointXYZ(0.1f, 0.1f, 1.0f));  // height 1: not a range image
  EXPECT_THROW(segment_cloud(flat, kinect_v1(), SegmentationParams{}), InvalidInput);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace occ_improve
