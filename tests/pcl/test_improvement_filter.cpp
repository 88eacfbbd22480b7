#include "occ_improve/pcl/improvement_filter.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/sample_scene.hpp"
#include "support/test_data.hpp"

#include <pcl/common/io.h>
#include <pcl/filters/random_sample.h>
#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <map>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>

namespace occ_improve {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Cloud::Ptr sample_cloud() {
  const sample::SampleFrame frame = sample::generate_scene();
  return Cloud::Ptr(new Cloud(organized_cloud(frame.points(), frame.intrinsics.width, frame.intrinsics.height)));
}

/// Indices of the points that have a ray (finite improvement in the companion cloud).
pcl::Indices with_ray(const pcl::PointCloud<PointImprovement>& improvement) {
  pcl::Indices out;
  for (std::size_t i = 0; i < improvement.size(); ++i)
    if (std::isfinite(improvement[i].improvement)) out.push_back(static_cast<pcl::index_t>(i));
  return out;
}

double mean_improvement(const pcl::PointCloud<PointImprovement>& improvement, const pcl::Indices& indices) {
  double sum = 0;
  std::size_t n = 0;
  for (const auto i : indices)
    if (std::isfinite(improvement[i].improvement)) {
      sum += improvement[i].improvement;
      ++n;
    }
  return n ? sum / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

/// The indices of `all` that are not in `a` (both ascending).
pcl::Indices minus(const pcl::Indices& all, const pcl::Indices& a) {
  pcl::Indices out;
  std::set_difference(all.begin(), all.end(), a.begin(), a.end(), std::back_inserter(out));
  return out;
}

pcl::Indices all_indices(std::size_t n) {
  pcl::Indices out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<pcl::index_t>(i);
  return out;
}

// The sample scene inserted once into a shared map (the expensive part); each test filters against it.
class ImprovementFilterTest : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    cloud_ = sample_cloud();
    mapper_ = std::make_shared<Mapper>(kinect_v1_paper());
    mapper_->insert(span_of(*cloud_));
  }
  static void TearDownTestSuite() {
    cloud_.reset();
    mapper_.reset();
  }
  /// A filter that reads the shared map without inserting again.
  static void configure(ImprovementFilter<pcl::PointXYZ>& filter) {
    filter.setMapper(mapper_);
    filter.setUpdateMap(false);
    filter.setInputCloud(cloud_);
  }

  static Cloud::Ptr cloud_;
  static std::shared_ptr<Mapper> mapper_;
};

Cloud::Ptr ImprovementFilterTest::cloud_;
std::shared_ptr<Mapper> ImprovementFilterTest::mapper_;

// A held-out trial: estimate_intrinsics_fit(cloud) with its default threw on every cloud (the default,
// infinity, is a limit the check refuses); it fits the sample's camera.
TEST(EstimateIntrinsicsFit, TheDefaultLimitFitsAPinholeCloud) {
  const sample::SampleFrame frame = sample::generate_scene();
  const IntrinsicsFit fit = estimate_intrinsics_fit(*sample_cloud());
  EXPECT_NEAR(fit.intrinsics.fx, frame.intrinsics.fx, 1e-3);
  EXPECT_NEAR(fit.intrinsics.cy, frame.intrinsics.cy, 1e-3);
  EXPECT_LT(fit.rms_residual_px, kMaxIntrinsicsFitResidualPx);
}

// An organized cloud of another size than the map's camera (another camera's image) was inserted without a
// word; it is refused as GrabberPipeline refuses it: no output, the map untouched.
TEST(ImprovementFilterCamera, AnOrganizedCloudOfAnotherSizeIsRefused) {
  const Cloud::Ptr full = sample_cloud();
  Cloud::Ptr half(new Cloud(full->width / 2, full->height / 2));
  for (std::uint32_t v = 0; v < half->height; ++v)
    for (std::uint32_t u = 0; u < half->width; ++u) half->at(u, v) = full->at(2 * u, 2 * v);
  ImprovementFilter<pcl::PointXYZ> filter;
  filter.setSensorPreset(kinect_v1(sample::generate_scene().intrinsics));
  filter.setTopFraction(0.2);
  filter.setInputCloud(half);
  pcl::Indices kept;
  filter.filter(kept);
  EXPECT_TRUE(kept.empty());
  EXPECT_EQ(filter.getMapper()->grid().touched_column_count(), 0u);
  filter.setInputCloud(full);  // the camera's own size goes in
  filter.filter(kept);
  EXPECT_FALSE(kept.empty());
  EXPECT_GT(filter.getMapper()->grid().touched_column_count(), 0u);
}

TEST_F(ImprovementFilterTest, ImprovementCloudIsAlignedWithTheInputAndTheMap) {
  ImprovementFilter<pcl::PointXYZ> filter;
  configure(filter);
  pcl::Indices kept;
  filter.filter(kept);
  const auto& improvement = filter.getImprovementCloud();
  ASSERT_EQ(improvement.size(), cloud_->size());
  EXPECT_EQ(improvement.width, cloud_->width);
  EXPECT_EQ(improvement.height, cloud_->height);
  const GridGeometry& geometry = mapper_->geometry();
  std::size_t without_ray = 0;
  for (std::size_t i = 0; i < cloud_->size(); i += 97) {
    const auto& p = (*cloud_)[i];
    ColumnIndex c = 0;
    if (!geometry.column_of(p.x, p.y, p.z, c)) {
      EXPECT_TRUE(std::isnan(improvement[i].improvement));
      continue;
    }
    EXPECT_EQ(improvement[i].improvement, mapper_->improvement().value[c]);
    EXPECT_EQ(improvement[i].probability, mapper_->surface().probability[c]);
    EXPECT_EQ(improvement[i].surface_depth, mapper_->surface().depth_m[c]);
    EXPECT_EQ(improvement[i].x, p.x);
  }
  for (const auto& q : improvement) without_ray += std::isnan(q.improvement) ? 1 : 0;
  EXPECT_EQ(filter.getPointsWithoutRay(), without_ray);
  EXPECT_GT(without_ray, 0u);  // the scene has no-return pixels (shadow bands, poster)
}

TEST_F(ImprovementFilterTest, TopFractionKeepsTheMostImprovingShare) {
  ImprovementFilter<pcl::PointXYZ> filter(true);
  configure(filter);
  filter.setTopFraction(0.2);
  pcl::Indices kept;
  filter.filter(kept);
  const auto& improvement = filter.getImprovementCloud();
  const pcl::Indices valid = with_ray(improvement);
  EXPECT_EQ(kept.size(), static_cast<std::size_t>(std::llround(0.2 * static_cast<double>(valid.size()))));
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  const pcl::Indices rest = minus(valid, kept);
  EXPECT_GT(mean_improvement(improvement, kept), mean_improvement(improvement, rest));
  // Removed indices: exactly the complement of the output.
  EXPECT_EQ(*filter.getRemovedIndices(), minus(all_indices(cloud_->size()), kept));
}

TEST_F(ImprovementFilterTest, NegativeIsTheComplementAmongPointsWithARay) {
  ImprovementFilter<pcl::PointXYZ> positive, negative(true);
  configure(positive);
  configure(negative);
  positive.setTopFraction(0.3);
  negative.setTopFraction(0.3);
  negative.setNegative(true);
  pcl::Indices kept, complement;
  positive.filter(kept);
  negative.filter(complement);
  EXPECT_EQ(complement, minus(with_ray(negative.getImprovementCloud()), kept));
  // Points without a ray are kept by neither, and are among the negative filter's removed indices.
  EXPECT_EQ(*negative.getRemovedIndices(), minus(all_indices(cloud_->size()), complement));
}

TEST_F(ImprovementFilterTest, KeepOrganizedKeepsTheImageWithNaNs) {
  ImprovementFilter<pcl::PointXYZ> filter;
  configure(filter);
  filter.setTopCount(5000);
  filter.setKeepOrganized(true);
  Cloud out;
  filter.filter(out);
  ASSERT_EQ(out.size(), cloud_->size());
  EXPECT_EQ(out.width, cloud_->width);
  EXPECT_EQ(out.height, cloud_->height);
  std::size_t finite = 0;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (std::isfinite(out[i].x)) {
      ++finite;
      EXPECT_EQ(out[i].x, (*cloud_)[i].x);
    }
  EXPECT_EQ(finite, 5000u);
  EXPECT_EQ(filter.getRemovedIndices()->size(), cloud_->size() - 5000);
}

TEST_F(ImprovementFilterTest, RangeAndContourSelectByValue) {
  ImprovementFilter<pcl::PointXYZ> range, contour;
  configure(range);
  configure(contour);
  range.setImprovementRange(0.05f, 0.5f);
  contour.setContourThreshold(-0.01f);
  pcl::Indices in_range, on_contour;
  range.filter(in_range);
  contour.filter(on_contour);
  const auto& improvement = range.getImprovementCloud();
  std::size_t expected_range = 0, expected_contour = 0;
  for (const auto& q : improvement) {
    if (!std::isfinite(q.improvement)) continue;
    expected_range += (q.improvement >= 0.05f && q.improvement <= 0.5f) ? 1 : 0;
    expected_contour += q.improvement < -0.01f ? 1 : 0;
  }
  EXPECT_EQ(in_range.size(), expected_range);
  EXPECT_EQ(on_contour.size(), expected_contour);
  EXPECT_GT(on_contour.size(), 0u) << "the scene's depth discontinuities give negative improvement";
  for (const auto i : in_range) EXPECT_TRUE(improvement[i].improvement >= 0.05f && improvement[i].improvement <= 0.5f);
  for (const auto i : on_contour) EXPECT_LT(improvement[i].improvement, -0.01f);
}

TEST_F(ImprovementFilterTest, IndicesRestrictTheSelection) {
  ImprovementFilter<pcl::PointXYZ> filter;
  configure(filter);
  pcl::IndicesPtr half(new pcl::Indices);
  for (std::size_t i = 0; i < cloud_->size(); i += 2) half->push_back(static_cast<pcl::index_t>(i));
  filter.setIndices(half);
  filter.setTopCount(1000);
  pcl::Indices kept;
  filter.filter(kept);
  EXPECT_EQ(kept.size(), 1000u);
  for (const auto i : kept) EXPECT_EQ(i % 2, 0);
}

TEST_F(ImprovementFilterTest, PointsWithoutARayAreNeverKept) {
  Cloud::Ptr cloud(new Cloud(*cloud_));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  (*cloud)[0] = pcl::PointXYZ(nan, nan, nan);
  (*cloud)[1] = pcl::PointXYZ(0.0f, 0.0f, -2.0f);  // behind the sensor: outside the field of view
  (*cloud)[2] = pcl::PointXYZ(0.0f, 0.0f, 0.0f);   // rho = 0
  for (bool negative : {false, true}) {
    ImprovementFilter<pcl::PointXYZ> filter;
    filter.setMapper(mapper_);
    filter.setUpdateMap(false);
    filter.setInputCloud(cloud);
    filter.setImprovementRange(-1e9f, 1e9f);  // everything with a ray
    filter.setNegative(negative);
    pcl::Indices kept;
    filter.filter(kept);
    for (const auto i : kept) EXPECT_GT(i, 2);
    EXPECT_GE(filter.getPointsWithoutRay(), 3u);
  }
}

TEST_F(ImprovementFilterTest, DefaultMapIsThePixelNativeKinectPreset) {
  ImprovementFilter<pcl::PointXYZ> filter;
  ASSERT_TRUE(filter.getMapper());
  EXPECT_EQ(filter.getMapper()->geometry().binning(), AngularBinning::pinhole);
  EXPECT_EQ(filter.getMapper()->geometry().params().camera, kinect_v1_intrinsics());
}

TEST_F(ImprovementFilterTest, ErrorsGiveAnEmptyOutput) {
  ImprovementFilter<pcl::PointXYZ> no_map;
  no_map.setMapper(nullptr);
  no_map.setInputCloud(cloud_);
  Cloud out;
  no_map.filter(out);
  EXPECT_TRUE(out.empty());

  ImprovementFilter<pcl::PointXYZ> bad_fraction;
  configure(bad_fraction);
  bad_fraction.setTopFraction(1.5);
  pcl::Indices kept{1, 2, 3};
  bad_fraction.filter(kept);
  EXPECT_TRUE(kept.empty());

  ImprovementFilter<pcl::PointXYZ> bad_range;
  configure(bad_range);
  bad_range.setImprovementRange(1.0f, 0.0f);
  bad_range.filter(out);
  EXPECT_TRUE(out.empty());

  EXPECT_THROW(keep_most_improving(*cloud_, mapper_, -0.1), InvalidParameter);
}

TEST(ImprovementFilter, UpdatesItsOwnOrASharedMap) {
  const Cloud::Ptr cloud = sample_cloud();
  // Own map from a preset: the filter inserts the frame, and a first view is all worth keeping.
  ImprovementFilter<pcl::PointXYZ> own;
  own.setSensorPreset(kinect_v1_paper());
  own.setInputCloud(cloud);
  own.setTopFraction(1.0);
  pcl::Indices kept;
  own.filter(kept);
  EXPECT_GT(own.getLastReport().insertion.points_inserted, 0u);
  EXPECT_EQ(own.getLastReport().insertion.points_received, cloud->size());
  EXPECT_EQ(kept.size(), cloud->size() - own.getPointsWithoutRay());

  // Shared map: the caller sees the insertion.
  auto shared = std::make_shared<Mapper>(kinect_v1_paper());
  ImprovementFilter<pcl::PointXYZ> filter;
  filter.setMapper(shared);
  filter.setInputCloud(cloud);
  filter.filter(kept);
  EXPECT_EQ(shared->surface().known_count(), own.getMapper()->surface().known_count());
  EXPECT_GT(shared->surface().known_count(), 0u);
}

// Selective sensing on real Kinect frames: keep 20 % of a frame, the part that improves the map most.
void check_selective_sensing(const pcl::PointCloud<pcl::PointXYZRGBA>::Ptr& cloud, const SensorPreset& preset) {
  auto mapper = std::make_shared<Mapper>(preset);
  const pcl::Indices kept = keep_most_improving(*cloud, mapper, 0.2);

  ImprovementFilter<pcl::PointXYZRGBA> reader(true);
  reader.setMapper(mapper);
  reader.setUpdateMap(false);
  reader.setInputCloud(cloud);
  reader.setTopFraction(0.2);
  pcl::Indices again;
  reader.filter(again);
  EXPECT_EQ(again, kept);  // the helper is the filter

  const auto& improvement = reader.getImprovementCloud();
  const pcl::Indices valid = with_ray(improvement);
  ASSERT_GT(valid.size(), 1000u);
  EXPECT_NEAR(static_cast<double>(kept.size()), 0.2 * static_cast<double>(valid.size()), 1.0);
  const pcl::Indices removed = minus(valid, kept);
  EXPECT_GT(mean_improvement(improvement, kept), mean_improvement(improvement, removed));
  EXPECT_EQ(*reader.getRemovedIndices(), minus(all_indices(cloud->size()), kept));

  ImprovementFilter<pcl::PointXYZRGBA> negative;
  negative.setMapper(mapper);
  negative.setUpdateMap(false);
  negative.setInputCloud(cloud);
  negative.setTopFraction(0.2);
  negative.setNegative(true);
  pcl::Indices complement;
  negative.filter(complement);
  EXPECT_EQ(complement, removed);

  ImprovementFilter<pcl::PointXYZRGBA> organized;
  organized.setMapper(mapper);
  organized.setUpdateMap(false);
  organized.setInputCloud(cloud);
  organized.setTopFraction(0.2);
  organized.setKeepOrganized(true);
  pcl::PointCloud<pcl::PointXYZRGBA> out;
  organized.filter(out);
  EXPECT_EQ(out.width, cloud->width);
  EXPECT_EQ(out.height, cloud->height);
  std::size_t finite = 0;
  for (const auto& p : out) finite += std::isfinite(p.x) ? 1 : 0;
  EXPECT_EQ(finite, kept.size());
}

// Selective sensing as make filter-eval runs it on the sample: the top fraction chosen against a
// kinect_v1 map as it is (empty at first), the frame not inserted by the filter.
struct SelectiveSensing {
  Cloud::Ptr cloud = sample_cloud();
  std::shared_ptr<Mapper> mapper = std::make_shared<Mapper>(kinect_v1(sample::generate_scene().intrinsics));
  ImprovementFilter<pcl::PointXYZ> filter;
  explicit SelectiveSensing(double fraction) {
    filter.setMapper(mapper);
    filter.setUpdateMap(false);
    filter.setInputCloud(cloud);
    filter.setTopFraction(fraction);
  }
};

// On a map that has seen nothing every ray ties at the no-data level: the kept points must be spread
// over the view (not the top rows, as a tie broken by point index did), as a jittered grid at the
// sampling's scale: 5 % of the rays is one point per 4 x 4 cell (floor(sqrt(20)) = 4), never two in one
// cell while cells are left, and fewer 8 x 8 blocks left empty than pcl::RandomSample leaves.
TEST(ImprovementFilter, TiesAreSpreadAsAJitteredGridAtTheSamplingScale) {
  SelectiveSensing run(0.05);
  const Cloud::Ptr& cloud = run.cloud;
  const std::shared_ptr<Mapper>& mapper = run.mapper;
  ImprovementFilter<pcl::PointXYZ>& filter = run.filter;
  pcl::Indices kept;
  filter.filter(kept);
  const pcl::Indices valid = with_ray(filter.getImprovementCloud());
  ASSERT_EQ(kept.size(), static_cast<std::size_t>(std::llround(0.05 * static_cast<double>(valid.size()))));
  const GridGeometry& geometry = mapper->geometry();
  const auto cell_of = [&](pcl::index_t i, int side) {
    ColumnIndex c = 0;
    const auto& p = (*cloud)[static_cast<std::size_t>(i)];
    EXPECT_TRUE(geometry.column_of(p.x, p.y, p.z, c));
    return std::make_pair(geometry.elevation_bin_of(c) / side, geometry.azimuth_bin_of(c) / side);
  };
  std::map<std::pair<int, int>, std::size_t> valid_per_cell, kept_per_cell;
  for (const auto i : valid) ++valid_per_cell[cell_of(i, 4)];
  ASSERT_GT(valid_per_cell.size(), kept.size());  // one round of cells is enough
  std::size_t top_half = 0;
  for (const auto i : kept) {
    top_half += static_cast<std::size_t>(i) < cloud->size() / 2 ? 1 : 0;
    EXPECT_EQ(++kept_per_cell[cell_of(i, 4)], 1u);
  }
  EXPECT_NEAR(static_cast<double>(top_half), kept.size() / 2.0, kept.size() / 10.0);

  // Empty 8 x 8 blocks among those with at least 48 rays (2.4 kept points expected): the jittered grid
  // leaves almost none, a random sample of as many points a few per cent of them (75 of the sample's).
  pcl::RandomSample<pcl::PointXYZ> random;
  random.setInputCloud(cloud);
  random.setSample(static_cast<unsigned int>(kept.size()));
  random.setSeed(1);
  pcl::Indices random_kept;
  random.filter(random_kept);
  std::map<std::pair<int, int>, std::size_t> valid_per_block;
  for (const auto i : valid) ++valid_per_block[cell_of(i, 8)];
  const auto empty_blocks = [&](const pcl::Indices& chosen) {
    std::map<std::pair<int, int>, std::size_t> chosen_per_block;
    for (const auto i : chosen)
      if (!std::isnan(filter.getImprovementCloud()[static_cast<std::size_t>(i)].improvement))
        ++chosen_per_block[cell_of(i, 8)];
    std::size_t empty = 0;
    for (const auto& [block, rays] : valid_per_block) empty += rays >= 48 && chosen_per_block.count(block) == 0 ? 1 : 0;
    return empty;
  };
  const std::size_t ours = empty_blocks(kept), theirs = empty_blocks(random_kept);
  EXPECT_GT(theirs, 30u);
  EXPECT_LT(ours * 10, theirs);
  pcl::Indices again;
  filter.filter(again);
  EXPECT_EQ(again, kept);  // deterministic
}

// A cell that holds a sample measures it again before a ray beside it (header, "better"): at the
// sampling scale the rays beside a sample are predicted from it. The first 5 % call on an empty map
// spreads its points over the cells (all rays tie); once they are in the map, the same call on the same
// points keeps again every one whose ray became a sample (a return carved away by a farther neighbour's
// OPDF across a depth step is none), although each of them now has a lower improvement than its
// unmeasured neighbours (0.138 against 0.324).
TEST(ImprovementFilter, ACellsSampleIsMeasuredAgainBeforeTheRaysBesideIt) {
  SelectiveSensing run(0.05);
  const Cloud::Ptr& cloud = run.cloud;
  const std::shared_ptr<Mapper>& mapper = run.mapper;
  pcl::Indices first;
  run.filter.filter(first);
  ASSERT_FALSE(first.empty());
  Cloud kept_points;
  pcl::copyPointCloud(*cloud, first, kept_points);
  mapper->insert(span_of(kept_points));
  pcl::Indices sampled;
  for (const auto i : first) {
    ColumnIndex c = 0;
    const auto& p = (*cloud)[static_cast<std::size_t>(i)];
    ASSERT_TRUE(mapper->geometry().column_of(p.x, p.y, p.z, c));
    if (is_depth_sample(mapper->surface(), c)) sampled.push_back(i);
  }
  EXPECT_GT(sampled.size(), first.size() * 8 / 10);

  pcl::Indices second;
  run.filter.filter(second);
  EXPECT_EQ(second.size(), first.size());
  EXPECT_TRUE(std::includes(second.begin(), second.end(), sampled.begin(), sampled.end()));
  // Not by the improvement: the cells' other rays at the no-data level (0.324) outrank the samples (seen
  // once, 0.138), and outnumber them.
  const auto& improvement = run.filter.getImprovementCloud();
  float highest_sampled = -std::numeric_limits<float>::infinity();
  for (const auto i : sampled) highest_sampled = std::max(highest_sampled, improvement[static_cast<std::size_t>(i)].improvement);
  std::size_t outranking = 0;
  for (const auto i : minus(with_ray(improvement), second))
    outranking += improvement[static_cast<std::size_t>(i)].improvement > highest_sampled + 0.1f ? 1 : 0;
  EXPECT_GT(outranking, second.size());
}

// The default map is Kinect v1's nominal camera (fx 525) until the first organized cloud: the sample's
// camera (fx 585) replaces it, so every point lies on its own ray. A cloud that fits no camera (its points
// shuffled) leaves the nominal one; a camera given by the user is kept whatever the cloud.
TEST(ImprovementFilter, TheDefaultMapTakesTheCloudsCamera) {
  const Cloud::Ptr cloud = sample_cloud();
  const PinholeIntrinsics camera = sample::generate_scene().intrinsics;
  ImprovementFilter<pcl::PointXYZ> filter;
  filter.setInputCloud(cloud);
  filter.setTopFraction(0.05);
  pcl::Indices kept;
  filter.filter(kept);
  ASSERT_FALSE(kept.empty());
  ASSERT_TRUE(filter.getMapper()->geometry().params().camera);
  EXPECT_TRUE(same_camera(*filter.getMapper()->geometry().params().camera, camera));
  const GridGeometry& geometry = filter.getMapper()->geometry();
  for (const auto i : kept) {
    ColumnIndex c = 0;
    const auto& p = (*cloud)[static_cast<std::size_t>(i)];
    ASSERT_TRUE(geometry.column_of(p.x, p.y, p.z, c));
    EXPECT_EQ(c, static_cast<ColumnIndex>(i));
  }
  EXPECT_EQ(filter.getMapper()->grid().touched_column_count() > 0, true);

  const PinholeIntrinsics nominal = *kinect_v1().geometry.camera;
  Cloud::Ptr shuffled(new Cloud(*cloud));
  std::mt19937 random(7);
  std::shuffle(shuffled->points.begin(), shuffled->points.end(), random);
  ImprovementFilter<pcl::PointXYZ> unfitted;
  unfitted.setInputCloud(shuffled);
  unfitted.filter(kept);
  EXPECT_FALSE(kept.empty());
  EXPECT_TRUE(same_camera(*unfitted.getMapper()->geometry().params().camera, nominal));
  ImprovementFilter<pcl::PointXYZ> given;
  given.setSensorPreset(kinect_v1());
  given.setInputCloud(cloud);
  given.filter(kept);
  EXPECT_TRUE(same_camera(*given.getMapper()->geometry().params().camera, nominal));
}

// An index list as long as the cloud is not the whole cloud unless it is 0, 1, ..., n - 1: repeated
// indices insert what they name, and a point they leave out is not inserted.
TEST(ImprovementFilter, IndicesAsLongAsTheCloudInsertWhatTheyName) {
  const Cloud::Ptr cloud = sample_cloud();
  const std::size_t middle = cloud->size() / 2 + cloud->width / 2;  // a return away from the image border
  ASSERT_GT((*cloud)[middle].z, 0.0f);
  pcl::IndicesPtr indices(new pcl::Indices(cloud->size(), static_cast<pcl::index_t>(middle)));
  ImprovementFilter<pcl::PointXYZ> filter;
  filter.setSensorPreset(kinect_v1(sample::generate_scene().intrinsics));
  filter.setInputCloud(cloud);
  filter.setIndices(indices);
  pcl::Indices kept;
  filter.filter(kept);
  EXPECT_EQ(filter.getMapper()->grid().touched_column_count(), 9u);  // one return's 3 x 3 columns
  EXPECT_EQ(filter.getLastReport().insertion.points_received, cloud->size());
}

TEST(ImprovementFilterRealData, SelectiveSensingOnFivePeople) {
  OCC_REQUIRE_DATA(path, "kinect/pcl_test/five_people.pcd");
  pcl::PointCloud<pcl::PointXYZRGBA>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZRGBA>);
  ASSERT_EQ(pcl::io::loadPCDFile(path, *cloud), 0);
  check_selective_sensing(cloud, kinect_v1());
}

TEST(ImprovementFilterRealData, SelectiveSensingOnA7ScenesFrameAfterAnother) {
  OCC_REQUIRE_DATA(first, "sequences/7scenes_redkitchen/frames/frame-000150.depth.png");
  OCC_REQUIRE_DATA(second, "sequences/7scenes_redkitchen/frames/frame-000151.depth.png");
  OCC_REQUIRE_DATA(intrinsics_path, "sequences/7scenes_redkitchen/camera-intrinsics.txt");
  const PinholeIntrinsics intrinsics = read_intrinsics_file(intrinsics_path);
  const SensorPreset preset = kinect_v1(intrinsics);
  // The map already holds frame 150; selective sensing then picks what frame 151 adds.
  auto mapper = std::make_shared<Mapper>(preset);
  const LoadedFrame frame150 = load_depth_frame(first, intrinsics, DepthEncoding::millimetres);
  mapper->insert(span_of(frame150.cloud));
  const LoadedFrame frame151 = load_depth_frame(second, intrinsics, DepthEncoding::millimetres);
  pcl::PointCloud<pcl::PointXYZRGBA>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZRGBA>);
  pcl::copyPointCloud(frame151.cloud, *cloud);

  ImprovementFilter<pcl::PointXYZRGBA> filter(true);
  filter.setMapper(mapper);
  filter.setInputCloud(cloud);
  filter.setTopFraction(0.2);
  pcl::Indices kept;
  filter.filter(kept);
  const auto& improvement = filter.getImprovementCloud();
  const pcl::Indices removed = minus(with_ray(improvement), kept);
  ASSERT_FALSE(kept.empty());
  EXPECT_GT(mean_improvement(improvement, kept), mean_improvement(improvement, removed));
}

}  // namespace
}  // namespace occ_improve

namespace occ_improve {
namespace {

// Every instantiated point type filters the same way (a small camera keeps this fast).
template <typename PointT>
class ImprovementFilterTyped : public ::testing::Test {};
using PointTypes = ::testing::Types<pcl::PointXYZ, pcl::PointXYZI, pcl::PointXYZRGB, pcl::PointXYZRGBA, pcl::PointXYZL>;
TYPED_TEST_SUITE(ImprovementFilterTyped, PointTypes);

TYPED_TEST(ImprovementFilterTyped, TopFractionOnAStep) {
  PinholeIntrinsics k;
  k.fx = k.fy = 50.0;
  k.cx = 31.5;
  k.cy = 23.5;
  k.width = 64;
  k.height = 48;
  PinholePresetOptions options;
  options.depth_bins = 128;
  // A step: left half at 1.5 m, right half at 3 m (a depth discontinuity down the middle).
  typename pcl::PointCloud<TypeParam>::Ptr cloud(new pcl::PointCloud<TypeParam>);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const double z = u < k.width / 2 ? 1.5 : 3.0;
      TypeParam p;
      p.x = static_cast<float>((u - k.cx) / k.fx * z);
      p.y = static_cast<float>((v - k.cy) / k.fy * z);
      p.z = static_cast<float>(z);
      cloud->push_back(p);
    }
  cloud->width = static_cast<std::uint32_t>(k.width);
  cloud->height = static_cast<std::uint32_t>(k.height);
  ImprovementFilter<TypeParam> filter(true);
  filter.setSensorPreset(preset_from_pinhole(k, options));
  filter.setInputCloud(cloud);
  filter.setTopFraction(0.25);
  pcl::PointCloud<TypeParam> kept;
  filter.filter(kept);
  const std::size_t with_ray_count = cloud->size() - filter.getPointsWithoutRay();
  EXPECT_GT(with_ray_count, cloud->size() / 2);
  EXPECT_EQ(kept.size(), static_cast<std::size_t>(std::llround(0.25 * static_cast<double>(with_ray_count))));
  EXPECT_EQ(filter.getRemovedIndices()->size(), cloud->size() - kept.size());
  EXPECT_EQ(filter.getImprovementCloud().size(), cloud->size());
}

}  // namespace
}  // namespace occ_improve
