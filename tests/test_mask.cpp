// The validity / region-of-interest mask (mask.hpp) through the Mapper: rays outside it are not observable
// (NaN improvement), never ranked, never in a region, never planned; their points are left out.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sample_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace occ_improve {
namespace {

// The sample's left half of the image: a mask that cuts through data and no-data alike.
PixelMask left_half(const PinholeIntrinsics& k) {
  PixelMask mask;
  mask.width = k.width;
  mask.height = k.height;
  mask.valid.assign(static_cast<std::size_t>(k.width) * k.height, 0);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width / 2; ++u) mask.valid[static_cast<std::size_t>(v) * k.width + u] = 255;
  return mask;
}

TEST(Mask, ColumnsOutsideAreNotObservableAndTheirPointsAreLeftOut) {
  const sample::SampleFrame frame = sample::generate_scene();
  const std::vector<Eigen::Vector3f> points = frame.points();
  const PixelMask mask = left_half(frame.intrinsics);
  Mapper masked(kinect_v1(frame.intrinsics)), plain(kinect_v1(frame.intrinsics));
  const MapperReport r = masked.insert(PointSpan::from(points), {}, mask);
  const MapperReport all = plain.insert(PointSpan::from(points));
  // The valid points of the right half were left out, and only those.
  std::size_t right_valid = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    right_valid += !mask.valid[i] && is_valid_point(points[i].x(), points[i].y(), points[i].z());
  EXPECT_GT(right_valid, 50000u);
  EXPECT_EQ(r.points_masked, right_valid);
  EXPECT_EQ(r.insertion.points_inserted + r.points_masked, all.insertion.points_inserted);
  // Every point handed in is accounted for, the masked ones too.
  EXPECT_EQ(r.insertion.skipped_masked, right_valid);
  EXPECT_EQ(r.insertion.points_received, points.size());
  EXPECT_EQ(r.insertion.points_received, r.insertion.points_inserted + r.insertion.skipped_invalid +
                                             r.insertion.skipped_outside_fov + r.insertion.skipped_masked);

  const int w = frame.intrinsics.width;
  std::size_t nan = 0;
  for (std::size_t c = 0; c < masked.improvement().value.size(); ++c) {
    const bool inside = static_cast<int>(c % static_cast<std::size_t>(w)) < w / 2;
    EXPECT_EQ(std::isnan(masked.improvement().value[c]), !inside) << "column " << c;
    nan += std::isnan(masked.improvement().value[c]);
  }
  EXPECT_EQ(nan, mask.valid.size() - mask.valid_count());

  // Never ranked, never in a region, never planned: everything lies in the left half.
  for (const RankedRay& ray : top_rays(masked.improvement(), masked.surface(), 5000)) EXPECT_LT(ray.azimuth_bin, w / 2);
  const std::vector<Region> regions = find_regions(masked.geometry(), masked.improvement(), masked.surface());
  ASSERT_FALSE(regions.empty());
  for (const Region& region : regions) EXPECT_LT(region.max_u, w / 2);
  PlanRequest request;
  request.budget_rays = 20000;
  const Shot shot = plan_next_shot(masked.improvement(), ReturnRecord::for_grid(w, frame.intrinsics.height), request);
  ASSERT_FALSE(shot.columns.empty());
  for (const ColumnIndex c : shot.columns) EXPECT_LT(static_cast<int>(c % static_cast<ColumnIndex>(w)), w / 2);

  // Clearing the mask brings the values back (the right half, never inserted, is unknown: the no-data level),
  // in the same buffer (Python's copy=False views read it in place: a new one crashed a view).
  const float* buffer = masked.improvement().value.data();
  masked.clear_mask();
  EXPECT_EQ(masked.improvement().value.data(), buffer);
  for (const float v : masked.improvement().value) ASSERT_FALSE(std::isnan(v));
  EXPECT_GT(masked.improvement().value[static_cast<std::size_t>(240) * w + 600], 0.3f);
}

// The Mapper re-masks only the rays an insertion recomputed: after several insertions under a mask the
// improvement equals a full computation masked as a whole, value for value (NaN where masked).
TEST(Mask, IncrementalMaskingEqualsMaskingTheWholeMap) {
  const sample::SampleFrame frame = sample::generate_scene();
  const std::vector<Eigen::Vector3f> points = frame.points();
  const PixelMask mask = left_half(frame.intrinsics);
  Mapper mapper(kinect_v1(frame.intrinsics));
  mapper.set_mask(mask);
  const std::size_t half = points.size() / 2;
  mapper.insert(PointSpan{points.front().data(), half, 3});
  const MapperReport second = mapper.insert(PointSpan{points[half].data(), points.size() - half, 3});
  ASSERT_GT(second.rays_recomputed, 1000u);
  ImprovementMap whole = compute_improvement(mapper.geometry(), mapper.model(), mapper.surface());
  mask_improvement(mapper.column_mask(), whole);
  ASSERT_EQ(whole.value.size(), mapper.improvement().value.size());
  for (std::size_t c = 0; c < whole.value.size(); ++c) {
    const float got = mapper.improvement().value[c], want = whole.value[c];
    ASSERT_TRUE(std::isnan(got) ? std::isnan(want) : got == want) << "column " << c << ": " << got << " vs " << want;
  }
}

TEST(Mask, RefusesAnotherSizeAndAGridWithoutCamera) {
  const PinholeIntrinsics k = kinect_v1_intrinsics();
  Mapper mapper(kinect_v1(k));
  PixelMask small = left_half(k);
  small.width = 320;
  small.valid.resize(320 * 480);
  try {
    mapper.set_mask(small);
    FAIL() << "a 320 x 480 mask was taken for a 640 x 480 camera";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("mask is 320 x 480, the camera 640 x 480"), std::string::npos) << e.what();
  }
  Mapper paper(kinect_v1_paper());
  EXPECT_THROW(paper.set_mask(left_half(k)), InvalidParameter);
  PixelMask broken = left_half(k);
  broken.valid.pop_back();
  EXPECT_THROW(mapper.set_mask(broken), InvalidInput);
}

// A grid without a camera (a VLP-16's rings) takes its mask per column: a rear sector (a vehicle's own body)
// masked, its returns are left out and counted, its improvement is NaN, and no plan asks for it. A mask of
// another size is refused naming both sizes.
TEST(Mask, AGridWithoutCameraTakesAMaskPerColumn) {
  Mapper mapper(lidar_rings());
  const GridGeometry& g = mapper.geometry();
  const auto rear = [&](int a) { return a < g.width() / 8; };  // an eighth of the turn
  std::vector<std::uint8_t> valid(g.column_count(), 7);  // any nonzero byte is inside
  for (int e = 0; e < g.height(); ++e)
    for (int a = 0; a < g.width(); ++a)
      if (rear(a)) valid[g.column(a, e)] = 0;
  mapper.set_column_mask(valid);
  // One return per column on a 10 m cylinder around the sensor.
  std::vector<Eigen::Vector3f> points;
  std::size_t rear_points = 0;
  for (int e = 0; e < g.height(); ++e)
    for (int a = 0; a < g.width(); ++a) {
      const Eigen::Vector3d d = g.direction_at(g.azimuth().centre(a), g.elevation().centre(e));
      points.push_back((d * (10.0 / std::hypot(d.x(), d.z()))).cast<float>());
      rear_points += rear(a);
    }
  const MapperReport report = mapper.insert(PointSpan::from(points));
  EXPECT_EQ(report.points_masked, rear_points);
  EXPECT_EQ(report.insertion.points_inserted + report.points_masked, points.size());
  std::size_t unknown_inside = 0;
  for (int e = 0; e < g.height(); ++e)
    for (int a = 0; a < g.width(); ++a) {
      const ColumnIndex c = g.column(a, e);
      EXPECT_EQ(mapper.column_mask()[c], rear(a) ? 0 : 1);
      EXPECT_EQ(std::isnan(mapper.improvement().value[c]), rear(a)) << "column " << a << ", " << e;
      unknown_inside += !rear(a) && mapper.surface().unknown[c];
    }
  EXPECT_EQ(unknown_inside, 0u);
  PlanRequest request;
  request.budget_rays = 4096;
  const Shot shot = plan_next_shot(mapper.improvement(), ReturnRecord::for_grid(g.width(), g.height()), request);
  ASSERT_FALSE(shot.columns.empty());
  for (const ColumnIndex c : shot.columns) EXPECT_FALSE(rear(g.azimuth_bin_of(c)));
  valid.pop_back();
  try {
    mapper.set_column_mask(valid);
    FAIL() << "a mask one byte short was taken";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("column mask"), std::string::npos) << e.what();
  }
  // A camera's pixel mask names pixels this grid does not have.
  EXPECT_THROW(mapper.set_mask(left_half(kinect_v1_intrinsics())), InvalidParameter);
}

TEST(Mask, SphericalGridsMaskTheColumnsWhoseDirectionFallsInAMaskedPixel) {
  const sample::SampleFrame frame = sample::generate_scene();
  Mapper mapper(kinect_v1_spherical(frame.intrinsics));
  mapper.set_mask(left_half(frame.intrinsics));
  const GridGeometry& g = mapper.geometry();
  std::size_t checked = 0;
  for (int e = 0; e < g.height(); e += 7)
    for (int a = 0; a < g.width(); a += 7) {
      const Eigen::Vector3d d = g.direction(a, e);
      const double u = frame.intrinsics.fx * d.x() / d.z() + frame.intrinsics.cx;
      if (std::abs(u - (frame.intrinsics.width / 2 - 0.5)) < 1.0) continue;  // the cut itself
      const bool inside = g.observable(g.column(a, e)) && u < frame.intrinsics.width / 2 - 0.5;
      EXPECT_EQ(std::isnan(mapper.improvement().value[g.column(a, e)]), !inside) << a << "," << e;
      ++checked;
    }
  EXPECT_GT(checked, 1000u);
}

TEST(Mask, FinitePixelMaskIsTheOrganizedFramesValidPoints) {
  const sample::SampleFrame frame = sample::generate_scene();
  const std::vector<Eigen::Vector3f> points = frame.points();
  const PixelMask mask = finite_pixel_mask(PointSpan::from(points), frame.intrinsics.width, frame.intrinsics.height);
  for (std::size_t i = 0; i < points.size(); i += 97)
    EXPECT_EQ(mask.valid[i] != 0, frame.depth_m[i] > 0) << "pixel " << i;
  EXPECT_LT(mask.valid_count(), points.size());
  EXPECT_THROW(finite_pixel_mask(PointSpan::from(points), 100, 100), InvalidInput);
}

}  // namespace
}  // namespace occ_improve
