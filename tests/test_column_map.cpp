// The shared per-column map type and its one shape check (maps/column_map.hpp), and that the maps'
// readers refuse a map of another shape through it, naming both shapes.
#include "occ_improve/errors.hpp"
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/maps/column_map.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/multiscale.hpp"
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/planning/return_model.hpp"
#include "occ_improve/segmentation/segmentation.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sim/render.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <string>

namespace occ_improve {
namespace {

// The message of the InvalidInput `f` throws ("" when it throws none).
std::string invalid_input_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "";
}

TEST(ColumnMap, IndexesRowMajorAndFills) {
  ColumnMap<std::uint16_t> m = ColumnMap<std::uint16_t>::filled(3, 2, 7);
  EXPECT_EQ(m.size(), 6u);
  m.at(2, 1) = 9;
  EXPECT_EQ(m.values[5], 9);
  EXPECT_EQ(m.index(1, 1), 4u);
  EXPECT_EQ(m.at(0, 0), 7);
  const ColumnShape s = m.shape();
  EXPECT_EQ(s.width, 3);
  EXPECT_EQ(s.height, 2);
  EXPECT_EQ(s.values, 6u);
  ColumnMap<float> aggregate{2, 1, {0.5f, 1.5f}};  // stays an aggregate: {width, height, values}
  EXPECT_EQ(aggregate.at(1, 0), 1.5f);
}

TEST(ColumnMap, ShapeOfArraysReportsTheFirstArrayThatDoesNotFit) {
  EXPECT_EQ(ColumnShape::of_arrays(4, 3, {12, 12}).values, 12u);
  EXPECT_EQ(ColumnShape::of_arrays(4, 3, {12, 11, 10}).values, 11u);
  EXPECT_EQ(ColumnShape::of_grid(4, 3).values, 12u);
  EXPECT_EQ(ColumnShape::of_grid(-4, 3).count(), 0u);
}

TEST(ColumnMap, TheShapeCheckNamesBothShapes) {
  EXPECT_NO_THROW(require_shape("map", ColumnShape::of_grid(4, 3), "the grid", ColumnShape::of_grid(4, 3)));
  EXPECT_EQ(invalid_input_message([] {
              require_shape("surface map", ColumnShape::of_grid(20, 10), "the grid", ColumnShape::of_grid(30, 10));
            }),
            "surface map is 20 x 10, the grid 30 x 10");
  EXPECT_EQ(invalid_input_message([] { require_shape("surface map", ColumnShape::of_arrays(20, 10, {200, 150})); }),
            "surface map of 20 x 10 holds 150 values, not 200");
  EXPECT_EQ(invalid_input_message([] {
              require_shape("map", ColumnShape::of_grid(2, 2), "the improvement map", ColumnShape::of_arrays(2, 2, {3}));
            }),
            "the improvement map of 2 x 2 holds 3 values, not 4");
  EXPECT_EQ(invalid_input_message([] { require_shape("mask", ColumnShape::of_grid(-1, 2)); }),
            "mask has a negative size, -1 x 2");
}

// A map of another size, handed to each reader of maps: one message form, both shapes named.
TEST(ColumnMap, TheMapsReadersRefuseAnotherShapeNamingBoth) {
  GeometryParams gp;
  gp.azimuth_bins = 8;
  gp.elevation_bins = 6;
  gp.depth_bins = 16;
  const GridGeometry g(gp);
  const SensorModel model(SensorModelParams{});
  SurfaceMap surface;
  surface.width = 8;
  surface.height = 6;
  surface.depth_m.assign(48, 0.0f);
  surface.probability.assign(48, 0.5f);
  surface.bin.assign(48, -1);
  surface.unknown.assign(48, 1);
  const ImprovementMap improvement = compute_improvement(g, model, surface, 1);
  const ImprovementMap narrow{7, 6, std::vector<float>(42, 0.0f)};
  SurfaceMap torn = surface;
  torn.bin.pop_back();

  EXPECT_EQ(invalid_input_message([&] { compute_improvement(g, model, torn, 1); }),
            "surface map of 8 x 6 holds 47 values, not 48");
  ImprovementMap narrow_map = narrow;
  EXPECT_EQ(invalid_input_message([&] { update_improvement(g, model, surface, {}, narrow_map); }),
            "improvement map is 7 x 6, the grid 8 x 6");
  EXPECT_EQ(invalid_input_message([&] { segment_improvement(g, surface, narrow); }),
            "segment_improvement: improvement map is 7 x 6, the grid 8 x 6");
  EXPECT_EQ(invalid_input_message([&] { top_rays(narrow, surface, 3); }),
            "improvement map is 7 x 6, the surface map 8 x 6");
  EXPECT_EQ(invalid_input_message([&] { top_rays(improvement, torn, 3); }),
            "the surface map of 8 x 6 holds 47 values, not 48");
  EXPECT_EQ(invalid_input_message([&] { ImprovementPyramid(narrow, surface); }),
            "surface map is 8 x 6, the pyramid 7 x 6");
  EXPECT_EQ(invalid_input_message([&] { render_improvement(ImprovementMap{8, 6, std::vector<float>(5)}); }),
            "improvement map of 8 x 6 holds 5 values, not 48");
  EXPECT_EQ(invalid_input_message([&] { shot_scores(improvement, ReturnRecord::for_grid(8, 5)); }),
            "return record is 8 x 5, the improvement map 8 x 6");
  EXPECT_EQ(invalid_input_message([&] { ReturnRecord::for_grid(8, 6).check_matches(9, 6); }),
            "return record is 8 x 6, the grid 9 x 6");
  PredictedDepth predicted = predict_depth(surface);
  predicted.height = 5;
  EXPECT_NE(invalid_input_message([&] { depth_agreement(surface, predicted, model); })
                .find("depth_agreement: prediction of 8 x 5 holds 48 values, not 40"),
            std::string::npos);
  ImprovementMap masked = improvement;
  EXPECT_EQ(invalid_input_message([&] { mask_improvement(std::vector<std::uint8_t>(40, 1), masked); }),
            "column mask of 8 x 6 holds 40 values, not 48");
}

}  // namespace
}  // namespace occ_improve
