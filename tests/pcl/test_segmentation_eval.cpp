// The segmentation on real labelled clouds (mOSD) against ground truth and against PCL's recipe.
#include "occ_improve/errors.hpp"
#include "occ_improve/eval/segmentation_eval.hpp"
#include "occ_improve/pcl/cloud_segmentation.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "support/test_data.hpp"

#include <gtest/gtest.h>
#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <tuple>

namespace occ_improve {
namespace {

const char* const kClouds[] = {"learn0", "learn8", "learn16", "learn17", "learn22",
                               "learn25", "learn30", "learn33", "learn40", "learn44"};

// Issue 23's targets on mosd_learn: pooled mean F >= 0.90, >= 80 % of objects at F >= 0.75, and ours
// not more than 0.02 below PCL on any cloud.
TEST(SegmentationEval, OursMeetsThePooledTargetsAndPclOnEveryCloud) {
  OCC_REQUIRE_DATA(first, "segmentation/mosd_learn/learn0.pcd");
  const SegmentationParams ours = segmentation_defaults(kinect_v1());
  std::vector<SegmentationScore> ours_scores, pcl_scores;
  for (const char* name : kClouds) {
    const std::string path = test::data_file(std::string("segmentation/mosd_learn/") + name + ".pcd");
    ASSERT_FALSE(path.empty()) << name;
    const auto cloud = load_labelled_cloud(path);
    std::vector<std::uint32_t> truth(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) truth[i] = cloud[i].label;
    const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
    const auto result = segment_cloud(cloud, kinect_v1(estimate_intrinsics(cloud)), ours);
    ours_scores.push_back(evaluate_segmentation(truth, result.point_labels, w, h));
    pcl::PointCloud<pcl::PointXYZ> xyz;
    pcl::copyPointCloud(cloud, xyz);
    pcl_scores.push_back(evaluate_segmentation(truth, pcl_organized_segmentation(xyz).labels, w, h));
    EXPECT_GE(ours_scores.back().mean_f, pcl_scores.back().mean_f - 0.02) << name;
  }
  const PooledScore ours_pooled = pool_scores(ours_scores), pcl_pooled = pool_scores(pcl_scores);
  std::printf("pooled over %zu objects: ours F %.3f (%.2f at F >= 0.75), PCL F %.3f (%.2f)\n", ours_pooled.objects,
              ours_pooled.mean_f, ours_pooled.well_segmented_share, pcl_pooled.mean_f, pcl_pooled.well_segmented_share);
  EXPECT_EQ(ours_pooled.objects, 34u);
  EXPECT_GE(ours_pooled.mean_f, 0.90);  // measured 0.93
  EXPECT_GE(ours_pooled.well_segmented_share, 0.80);  // measured 0.97
  EXPECT_GT(ours_pooled.mean_f, pcl_pooled.mean_f);
}

// learn17: a cereal box lying on another. The crease cue gives each its own segment; without it they are
// one (the failure).
TEST(SegmentationEval, StackedBoxesOfLearn17AreSplitByTheCrease) {
  OCC_REQUIRE_DATA(path, "segmentation/mosd_learn/learn17.pcd");
  const auto cloud = load_labelled_cloud(path);
  std::vector<std::uint32_t> truth(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) truth[i] = cloud[i].label;
  const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
  SegmentationParams params = segmentation_defaults(kinect_v1());
  auto score = [&](const SegmentationParams& p) {
    return evaluate_segmentation(truth, segment_cloud(cloud, kinect_v1(estimate_intrinsics(cloud)), p).point_labels, w, h);
  };
  const SegmentationScore with = score(params);
  ASSERT_EQ(with.objects.size(), 2u);
  EXPECT_NE(with.objects[0].best_segment, with.objects[1].best_segment);
  for (const ObjectScore& o : with.objects) EXPECT_GE(o.f, 0.9) << o.ground_truth_label;
  params.split_concave_creases = false;
  const SegmentationScore without = score(params);
  EXPECT_EQ(without.objects[0].best_segment, without.objects[1].best_segment);
  EXPECT_LT(without.mean_f, 0.75);
}

// person.pcd (PCL's tutorial cloud, not in the evaluation): its back wall at 3-4 m. With a 2 cm crease
// arm at every range the noise there (17-23 mm) read as creases on 37 % of the rays beyond 2.5 m and cut
// them into 44 segments (plane removal off); the arm that grows with the noise leaves ~13 % and a few
// segments, while the table-top clouds of the evaluation (within 1.5 m) keep the arm of 2 cm (the test
// above). Likewise the plane's band: 6 mm took 41 % of the wall as the plane, the widening band all of it.
TEST(SegmentationEval, FarWallOfPersonIsNotCutByItsNoise) {
  OCC_REQUIRE_DATA(path, "kinect/pcl_tutorials/person.pcd");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(path, cloud), 0) << path;
  const SensorPreset preset = kinect_v1(estimate_intrinsics(cloud));
  const auto far_rays = [&](const SegmentationParams& params) {
    const CloudSegmentation result = segment_cloud(cloud, preset, params);
    const Segmentation& s = result.segmentation;
    EXPECT_EQ(s.label.size(), cloud.size());  // pixel-native: ray c is the cloud's point c
    std::size_t rays = 0, creases = 0, segments = 0;
    for (std::size_t c = 0; c < s.label.size(); ++c)
      if (s.label[c] != 0 && cloud[c].z > 2.5f) rays += 1, creases += s.crease[c];
    for (const Segment& segment : s.segments) segments += segment.mean_depth_m > 2.5 ? 1 : 0;
    return std::make_tuple(rays, static_cast<double>(creases) / static_cast<double>(std::max<std::size_t>(rays, 1)), segments,
                           s.plane_columns);
  };
  SegmentationParams params = segmentation_defaults(preset);
  const std::size_t plane = std::get<3>(far_rays(params));
  params.plane_distance_per_m2 = 0;
  const std::size_t narrow_plane = std::get<3>(far_rays(params));
  params = segmentation_defaults(preset);
  params.remove_dominant_plane = false;  // the wall would be the plane: creases are looked for off it
  const auto [rays, share, segments, no_plane] = far_rays(params);
  params.crease_arm_per_m2 = 0;
  const auto [short_rays, short_share, short_segments, still_no_plane] = far_rays(params);
  std::printf("person.pcd beyond 2.5 m: %zu rays, crease share %.3f, %zu segments (2 cm arm: %.3f, %zu); the wall as "
              "plane: %zu inliers (6 mm band: %zu)\n",
              rays, share, segments, short_share, short_segments, plane, narrow_plane);
  EXPECT_EQ(no_plane + still_no_plane, 0u);
  EXPECT_GT(plane, 2 * narrow_plane);  // measured 85 011 against 34 515
  EXPECT_GT(rays, 100000u);
  EXPECT_LT(share, 0.15);      // measured 0.127 (0.105 under a fixed 20 deg view angle)
  EXPECT_LE(segments, 16u);    // measured 13 (5 under a fixed 20 deg view angle, which cut fewer pieces)
  EXPECT_GT(short_share, 2 * share);
  EXPECT_GT(short_segments, 3 * segments);
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

TEST(SegmentationEval, UnlabelledBoundaryPixelsAreMisses) {
  // Objects 20 (columns 0-5) and 21 (columns 6-11): the ground-truth boundary pixels are columns 5 and 6.
  const int w = 12, h = 6;
  std::vector<std::uint32_t> truth(w * h), predicted(w * h);
  for (int i = 0; i < w * h; ++i) {
    truth[static_cast<std::size_t>(i)] = (i % w) < 6 ? 20 : 21;
    predicted[static_cast<std::size_t>(i)] = (i % w) < 6 ? 7 : 9;
  }
  EXPECT_DOUBLE_EQ(evaluate_segmentation(truth, predicted, w, h).boundary_recall, 1.0);
  // The prediction cuts between columns 3|4 (labels 7|8) and leaves column 5 unlabelled. Both boundary
  // columns lie within the 2 px tolerance of that cut, but column 5 is unlabelled: a miss. Recall 6 / 12.
  for (int v = 0; v < h; ++v) {
    predicted[static_cast<std::size_t>(v * w + 4)] = 8;
    predicted[static_cast<std::size_t>(v * w + 5)] = 0;
  }
  const SegmentationScore s = evaluate_segmentation(truth, predicted, w, h);
  EXPECT_NEAR(s.boundary_recall, 0.5, 1e-12);
  EXPECT_NEAR(s.boundary_precision, 1.0, 1e-12) << "the 3|4 cut lies within 2 px of the true boundary";
}

TEST(SegmentationEval, PoolingWeighsEveryObjectOfAtLeast100Points) {
  SegmentationScore a, b;
  auto object = [](std::size_t points, double f) {
    ObjectScore o;
    o.points = points;
    o.f = f;
    return o;
  };
  a.objects = {object(5000, 1.0), object(99, 0.0)};  // the 99-point object is left out
  b.objects = {object(100, 0.5), object(300, 0.8), object(200, 0.7)};
  const PooledScore pooled = pool_scores({a, b});
  EXPECT_EQ(pooled.objects, 4u);
  EXPECT_NEAR(pooled.mean_f, (1.0 + 0.5 + 0.8 + 0.7) / 4, 1e-12);
  EXPECT_NEAR(pooled.well_segmented_share, 2.0 / 4, 1e-12);
  EvaluationOptions all;
  all.min_object_points = 0;
  EXPECT_EQ(pool_scores({a, b}, all).objects, 5u);
  EXPECT_EQ(pool_scores({}).objects, 0u);
  EXPECT_EQ(pool_scores({}).mean_f, 0.0);
}

// occ_segment_eval's printed rows: per-cloud F as the library scores it, MEAN the mean of the per-cloud
// rows, POOLED the pooled objects, for both methods.
TEST(SegmentationEval, ToolPrintsPerCloudMeanAndPooledFigures) {
  OCC_REQUIRE_DATA(first, "segmentation/mosd_learn/learn0.pcd");
  const std::array<std::string, 2> names{"learn0", "learn17"};
  std::string arguments;
  std::vector<SegmentationScore> ours_scores, pcl_scores;
  for (const std::string& name : names) {
    const std::string path = test::data_file("segmentation/mosd_learn/" + name + ".pcd");
    ASSERT_FALSE(path.empty()) << name;
    arguments += " " + path;
    const auto cloud = load_labelled_cloud(path);
    std::vector<std::uint32_t> truth(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) truth[i] = cloud[i].label;
    const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
    const auto result = segment_cloud(cloud, kinect_v1(estimate_intrinsics(cloud)), segmentation_defaults(kinect_v1()));
    ours_scores.push_back(evaluate_segmentation(truth, result.point_labels, w, h));
    pcl::PointCloud<pcl::PointXYZ> xyz;
    pcl::copyPointCloud(cloud, xyz);
    pcl_scores.push_back(evaluate_segmentation(truth, pcl_organized_segmentation(xyz).labels, w, h));
  }
  const auto out_path = std::filesystem::temp_directory_path() / "occ_seg_eval_tool_output.txt";
  const std::string command = std::string(OCC_SEGMENT_EVAL_EXECUTABLE) + " -q" + arguments + " > " + out_path.string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(out_path);
  std::map<std::string, std::vector<double>> rows;  // "cloud method" -> numbers after the method
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string cloud, method;
    fields >> cloud >> method;
    if (method != "ours" && method != "pcl") continue;
    std::vector<double> values;
    for (double v; fields >> v;) values.push_back(v);
    rows[cloud + " " + method] = values;
  }
  std::filesystem::remove(out_path);
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto& ours = rows[names[k] + ".pcd ours"];
    const auto& pcl = rows[names[k] + ".pcd pcl"];
    ASSERT_EQ(ours.size(), 8u) << names[k];
    ASSERT_EQ(pcl.size(), 8u) << names[k];
    EXPECT_NEAR(ours[0], ours_scores[k].mean_f, 6e-4) << names[k];
    EXPECT_NEAR(ours[5], ours_scores[k].boundary_recall, 6e-4) << names[k];
    EXPECT_NEAR(pcl[0], pcl_scores[k].mean_f, 6e-4) << names[k];
    EXPECT_GT(ours[6], 0) << "segmentation ms";
    EXPECT_GT(ours[7], ours[6]) << "the frame's time includes the map";
  }
  ASSERT_EQ(rows["MEAN ours"].size(), 8u);
  EXPECT_NEAR(rows["MEAN ours"][0], (ours_scores[0].mean_f + ours_scores[1].mean_f) / 2, 1e-3);
  EXPECT_NEAR(rows["MEAN pcl"][0], (pcl_scores[0].mean_f + pcl_scores[1].mean_f) / 2, 1e-3);
  for (const auto& [method, scores] : {std::pair{std::string("ours"), ours_scores}, std::pair{std::string("pcl"), pcl_scores}}) {
    const PooledScore pooled = pool_scores(scores);
    const auto& row = rows["POOLED " + method];
    ASSERT_GE(row.size(), 3u) << method;
    EXPECT_NEAR(row[0], pooled.mean_f, 6e-4) << method;
    EXPECT_NEAR(row[1], pooled.well_segmented_share, 6e-3) << method;
    EXPECT_EQ(row[2], static_cast<double>(pooled.objects)) << method;
    EXPECT_EQ(pooled.objects, 4u) << "learn0 and learn17 hold two objects of >= 100 points each";
  }
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
  // Labels all below the first object's (found by a bad-input trial): it scored F = 0 and weighed in the
  // MEAN; the tool now refuses it, naming the cloud, and prints no score.
  pcl::PointCloud<pcl::PointXYZRGBL> no_object(64, 48);
  for (std::size_t i = 0; i < no_object.size(); ++i) {
    no_object[i].x = 0.01f * static_cast<float>(i % 64) - 0.3f;
    no_object[i].y = 0.01f * static_cast<float>(i / 64) - 0.2f;
    no_object[i].z = 1.0f;
    no_object[i].label = i % 2 ? 1 : 0;  // table and nothing
  }
  const std::string table_only = (dir / "table_only.pcd").string();
  ASSERT_EQ(pcl::io::savePCDFileBinary(table_only, no_object), 0);
  const auto out_path = dir / "out.txt";
  const std::string command = std::string(OCC_SEGMENT_EVAL_EXECUTABLE) + " -q " + table_only + " > " +
                              out_path.string() + " 2>&1";
  EXPECT_NE(std::system(command.c_str()), 0);
  std::ifstream in(out_path);
  const std::string output((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(output.find("table_only.pcd"), std::string::npos) << output;
  EXPECT_NE(output.find("no ground-truth object in it (every label is below 20"), std::string::npos) << output;
  EXPECT_EQ(output.find("MEAN"), std::string::npos) << output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace occ_improve
