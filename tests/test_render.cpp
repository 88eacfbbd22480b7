// Rendering the maps into images (the PNG files of them: tests/io/test_png.cpp).
#include "occ_improve/errors.hpp"
#include "occ_improve/sim/render.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace occ_improve {
namespace {

SurfaceMap three_columns() {
  SurfaceMap s;
  s.width = 3;
  s.height = 1;
  s.depth_m = {0.0f, 2.5f, 7.0f};
  s.probability = {0.0f, 0.5f, 1.0f};
  s.bin = {-1, 10, 20};
  s.unknown = {1, 0, 0};
  return s;
}

TEST(Render, DepthAndOccupancyScales) {
  const SurfaceMap s = three_columns();
  const Image d = render_depth(s, 5.0);
  EXPECT_EQ(d.channels, 1);
  EXPECT_EQ(d.pixels, (std::vector<std::uint8_t>{0, 128, 255}));  // black, mid, clipped white
  const Image o = render_occupancy(s);
  EXPECT_EQ(o.pixels, (std::vector<std::uint8_t>{0, 128, 255}));
  EXPECT_THROW(render_depth(s, 0.0), InvalidParameter);
  EXPECT_THROW(render_depth(s, std::nan("")), InvalidParameter);
}

TEST(Render, ImprovementColoursFollowTheBreakpoints) {
  using C = std::array<std::uint8_t, 3>;
  EXPECT_EQ(improvement_colour(0.0f), (C{0, 200, 0}));      // green
  EXPECT_EQ(improvement_colour(0.1f), (C{255, 255, 0}));    // yellow
  EXPECT_EQ(improvement_colour(0.26f), (C{255, 160, 0}));   // orange
  EXPECT_EQ(improvement_colour(0.31f), (C{255, 100, 0}));   // dark orange (rays seen once, off centre)
  EXPECT_EQ(improvement_colour(0.324f), (C{255, 0, 0}));    // red (no-data rays)
  EXPECT_EQ(improvement_colour(-1.0f), (C{0, 0, 128}));     // dark blue
  const C slight = improvement_colour(-0.05f), strong = improvement_colour(-0.2f);
  EXPECT_GT(slight[2], slight[0]);                           // negative: blue shades
  EXPECT_GT(strong[2], strong[1]);
  EXPECT_LT(strong[1], slight[1]);                           // deeper blue for larger magnitude
  const C once = improvement_colour(0.13f);                  // between yellow and orange
  EXPECT_EQ(once[0], 255);
  EXPECT_GT(once[1], 160);
  EXPECT_LT(once[1], 255);
  ImprovementMap m{2, 1, {0.0f, 0.324f}};
  const Image im = render_improvement(m);
  EXPECT_EQ(im.channels, 3);
  EXPECT_EQ(im.pixels, (std::vector<std::uint8_t>{0, 200, 0, 255, 0, 0}));
  m.value.pop_back();
  EXPECT_THROW(render_improvement(m), InvalidInput);
}

TEST(Render, LegendShowsTheColourBarAndLabels) {
  const Image legend = render_improvement_legend();
  ASSERT_EQ(legend.channels, 3);
  ASSERT_GT(legend.width, 300);
  const auto pixel = [&](int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(legend.width) + static_cast<std::size_t>(x)) * 3;
    return std::array<std::uint8_t, 3>{legend.pixels[i], legend.pixels[i + 1], legend.pixels[i + 2]};
  };
  // Find the bar: the row through its middle has the colour map's colours from left to right, -0.4 .. 0.4.
  int bar_row = -1, first = -1, last = -1;
  for (int y = 0; y < legend.height && bar_row < 0; ++y)
    for (int x = 0; x < legend.width; ++x)
      if (pixel(x, y) == improvement_colour(-0.4f)) {
        bar_row = y;
        break;
      }
  ASSERT_GE(bar_row, 0);
  for (int x = 0; x < legend.width; ++x)
    if (pixel(x, bar_row) != std::array<std::uint8_t, 3>{255, 255, 255}) {
      if (first < 0) first = x;
      last = x;
    }
  const int span = last - first;
  ASSERT_GT(span, 200);
  for (int tenths = -4; tenths <= 4; ++tenths) {
    const int x = first + (tenths + 4) * span / 8;
    EXPECT_EQ(pixel(x, bar_row), improvement_colour(0.1f * static_cast<float>(tenths))) << tenths;
    // Black label pixels below each tick.
    int dark = 0;
    for (int y = bar_row; y < legend.height; ++y)
      for (int dx = -8; dx <= 8; ++dx) {
        const auto p = pixel(std::min(legend.width - 1, std::max(0, x + dx)), y);
        dark += p == std::array<std::uint8_t, 3>{0, 0, 0};
      }
    EXPECT_GT(dark, 10) << "label of " << tenths;
  }
}

TEST(Render, NotObservableColumnsAreNeutralGreyNotTheNoDataRed) {
  const auto grey = improvement_colour(std::numeric_limits<float>::quiet_NaN());
  EXPECT_EQ(grey, (std::array<std::uint8_t, 3>{kNotObservableGrey, kNotObservableGrey, kNotObservableGrey}));
  EXPECT_NE(grey, improvement_colour(0.324f));
  EXPECT_EQ(improvement_colour(0.324f), (std::array<std::uint8_t, 3>{255, 0, 0}));
}

TEST(Render, OverlayBlendsTheColoursOverTheImage) {
  ImprovementMap map;
  map.width = 2;
  map.height = 1;
  map.value = {0.324f, 0.0f};
  Image colour;
  colour.width = 2;
  colour.height = 1;
  colour.channels = 3;
  colour.pixels = {0, 0, 0, 200, 200, 200};
  const Image half = render_overlay(map, colour);
  EXPECT_EQ(half.pixels[0], 128);  // red 255 over black
  EXPECT_EQ(half.pixels[1], 0);
  EXPECT_EQ(half.pixels[4], 200);  // green 200 over grey 200
  EXPECT_EQ(render_overlay(map, colour, 0.0).pixels, colour.pixels);
  colour.width = 1;
  EXPECT_THROW(render_overlay(map, colour), InvalidInput);
  colour.width = 2;
  EXPECT_THROW(render_overlay(map, colour, 1.5), InvalidParameter);
}

TEST(Render, CurveRunsFromTheFirstPointToTheLastInsideItsFrame) {
  const Image im = render_curve({0, 1, 2}, {10, 5, 0}, 100, 50);
  ASSERT_EQ(im.channels, 3);
  const auto pixel = [&](int x, int y) {
    const std::size_t i = (static_cast<std::size_t>(y) * 100 + static_cast<std::size_t>(x)) * 3;
    return std::array<std::uint8_t, 3>{im.pixels[i], im.pixels[i + 1], im.pixels[i + 2]};
  };
  const std::array<std::uint8_t, 3> blue{0, 64, 255};
  EXPECT_EQ(pixel(4, 4), blue);     // highest y at the first x: top left inside the margin
  EXPECT_EQ(pixel(95, 45), blue);   // lowest y at the last x: bottom right
  EXPECT_EQ(pixel(50, 25), blue);   // a straight line through the middle
  EXPECT_EQ(pixel(0, 0), (std::array<std::uint8_t, 3>{0, 0, 0}));  // the frame
  EXPECT_EQ(pixel(90, 5), (std::array<std::uint8_t, 3>{255, 255, 255}));
  // A series constant to six digits is a flat line at the top (the axis holds 0), not its rounding.
  const Image flat = render_curve({0, 1, 2}, {293222.0, 293222.0 - 1e-6, 293222.0 + 1e-6}, 100, 50);
  for (int y = 1; y < 49; ++y) {
    const std::size_t i = (static_cast<std::size_t>(y) * 100 + 50) * 3;
    const bool blue = flat.pixels[i] == 0 && flat.pixels[i + 1] == 64;
    EXPECT_EQ(blue, y == 4) << "row " << y;
  }
  EXPECT_THROW(render_curve({0}, {0}), InvalidInput);
  EXPECT_THROW(render_curve({0, 1}, {0}), InvalidInput);
  EXPECT_THROW(render_curve({0, 1}, {0, 1}, 8, 8), InvalidParameter);
}

}  // namespace
}  // namespace occ_improve
