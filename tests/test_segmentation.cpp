// Segmentation along negative-improvement contours on the generated scene.
#include "occ_improve/errors.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/segmentation.hpp"

#include <gtest/gtest.h>


namespace occ_improve {
namespace {

struct Scene {
  SensorPreset preset;
  Mapper mapper;
  explicit Scene(const SensorPreset& p) : preset(p), mapper(p) {
    const auto points = sample::generate_scene().points();
    mapper.insert(PointSpan::from(points));
  }
  std::uint32_t label_at(const Segmentation& s, double x, double y, double z) const {
    ColumnIndex c = 0;
    EXPECT_TRUE(mapper.geometry().column_of(x, y, z, c));
    return s.label[c];
  }
};

// The occluders stand on the floor: where they touch it there is no depth step, so this method alone joins
// them to the floor (and RANSAC takes the larger wall as the dominant plane). What must hold: they are
// cut from the wall behind them by their contours. docs/SEGMENTATION.md discusses the limitation.
TEST(Segmentation, OccludersAreCutFromTheBackground) {
  const Scene scene(kinect_v1(sample::generate_scene().intrinsics));
  SegmentationParams params = segmentation_defaults(scene.preset);
  params.remove_dominant_plane = true;
  const Segmentation s = segment_improvement(scene.mapper.geometry(), scene.mapper.surface(),
                                             scene.mapper.improvement(), params);
  const std::uint32_t box = scene.label_at(s, -0.6, 0.45, 1.6), pole = scene.label_at(s, 0.4, -0.5, 2.3),
                      wall = scene.label_at(s, -2.0, -1.0, 4.2), floor = scene.label_at(s, 0.0, 0.8, 3.0);
  for (std::uint32_t l : {box, pole, wall, floor}) EXPECT_NE(l, 0u);
  EXPECT_NE(box, wall);
  EXPECT_NE(pole, wall);
  EXPECT_GT(s.contour_columns, 0u);
  // Every valid ray is labelled, and the segment table matches the labels.
  std::size_t labelled = 0;
  for (std::uint32_t l : s.label) labelled += l != 0 ? 1 : 0;
  EXPECT_EQ(labelled, s.valid_columns);
  std::size_t in_segments = 0;
  for (const Segment& seg : s.segments) in_segments += seg.columns;
  EXPECT_EQ(in_segments, labelled);
}

TEST(Segmentation, EmptyMapGivesNoSegmentsAndBadParamsThrow) {
  const Mapper empty(kinect_v1_paper());
  const Segmentation s = segment_improvement(empty.geometry(), empty.surface(), empty.improvement());
  EXPECT_TRUE(s.segments.empty());
  SegmentationParams bad;
  bad.contour_improvement_below = 0.1f;  // contours are a negative band
  EXPECT_THROW(segment_improvement(empty.geometry(), empty.surface(), empty.improvement(), bad), InvalidParameter);
  bad = {};
  bad.min_segment_columns = 0;
  EXPECT_THROW(bad.validate(), InvalidParameter);
  ImprovementMap wrong = empty.improvement();
  wrong.value.pop_back();
  EXPECT_THROW(segment_improvement(empty.geometry(), empty.surface(), wrong), InvalidInput);
}

TEST(Segmentation, LabelColoursAreStableAndNeverBlack) {
  EXPECT_EQ(segment_colour(0), (std::array<std::uint8_t, 3>{0, 0, 0}));
  for (std::uint32_t l = 1; l < 50; ++l) {
    const auto c = segment_colour(l);
    EXPECT_GT(int(c[0]) + int(c[1]) + int(c[2]), 0);
    EXPECT_EQ(c, segment_colour(l));
    EXPECT_NE(c, segment_colour(l + 1));
  }
}

}  // namespace
}  // namespace occ_improve
