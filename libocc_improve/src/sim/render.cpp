#include "occ_improve/sim/render.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace occ_improve {
namespace {

std::uint8_t unit_to_byte(double v) {  // [0, 1] -> [0, 255], clipped, rounded
  v = std::isnan(v) ? 0.0 : std::min(1.0, std::max(0.0, v));
  return static_cast<std::uint8_t>(std::lround(v * 255.0));
}

Image grey_image(int width, int height) {
  Image im;
  im.width = width;
  im.height = height;
  im.channels = 1;
  im.pixels.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  return im;
}

void require_consistent(const SurfaceMap& s) { require_shape("surface map", s.shape()); }

struct ColourStop {
  float value;
  std::uint8_t r, g, b;
};
// The breakpoints of render.hpp / docs/METHOD.md.
constexpr ColourStop kColourStops[] = {
    {-0.3f, 0, 0, 128},    {-0.1f, 0, 64, 255},    {0.0f, 0, 200, 0},    {0.1f, 255, 255, 0},
    {0.26f, 255, 160, 0},  {0.31f, 255, 100, 0},   {0.322f, 255, 0, 0},
};

// ---- A 3 x 5 pixel font for the legend's labels.
const char* glyph(char c) {
  switch (c) {
    case '0': return "111101101101111";
    case '1': return "010110010010111";
    case '2': return "111001111100111";
    case '3': return "111001111001111";
    case '4': return "101101111001001";
    case '5': return "111100111001111";
    case '6': return "111100111101111";
    case '7': return "111001001001001";
    case '8': return "111101111101111";
    case '9': return "111101111001111";
    case '-': return "000000111000000";
    case '.': return "000000000000010";
    default: return "000000000000000";
  }
}

void fill(Image& im, int x0, int y0, int w, int h, const std::array<std::uint8_t, 3>& rgb) {
  for (int y = std::max(0, y0); y < std::min(im.height, y0 + h); ++y)
    for (int x = std::max(0, x0); x < std::min(im.width, x0 + w); ++x)
      for (int ch = 0; ch < 3; ++ch)
        im.pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(im.width) + static_cast<std::size_t>(x)) * 3 +
                  static_cast<std::size_t>(ch)] = rgb[static_cast<std::size_t>(ch)];
}

// Text centred on x, top at y, each font pixel drawn as scale x scale.
void draw_text(Image& im, const std::string& text, int centre_x, int y, int scale) {
  const int advance = 4 * scale;
  int x = centre_x - (static_cast<int>(text.size()) * advance - scale) / 2;
  for (const char c : text) {
    const char* g = glyph(c);
    for (int row = 0; row < 5; ++row)
      for (int col = 0; col < 3; ++col)
        if (g[row * 3 + col] == '1') fill(im, x + col * scale, y + row * scale, scale, scale, {0, 0, 0});
    x += advance;
  }
}

}  // namespace

std::array<std::uint8_t, 3> improvement_colour(float value) {
  if (std::isnan(value)) return {kNotObservableGrey, kNotObservableGrey, kNotObservableGrey};
  const auto& first = kColourStops[0];
  const auto& last = kColourStops[std::size(kColourStops) - 1];
  if (value <= first.value) return {first.r, first.g, first.b};
  if (value >= last.value) return {last.r, last.g, last.b};
  std::size_t k = 1;
  while (value > kColourStops[k].value) ++k;
  const ColourStop& lo = kColourStops[k - 1];
  const ColourStop& hi = kColourStops[k];
  const float t = (value - lo.value) / (hi.value - lo.value);
  const auto mix = [t](std::uint8_t a, std::uint8_t b) {
    return static_cast<std::uint8_t>(std::lround(a + t * (static_cast<float>(b) - a)));
  };
  return {mix(lo.r, hi.r), mix(lo.g, hi.g), mix(lo.b, hi.b)};
}

Image render_depth(const SurfaceMap& surface, double depth_max_m) {
  detail::require_parameter(std::isfinite(depth_max_m) && depth_max_m > 0, "depth_max_m", depth_max_m,
                            "finite and > 0");
  require_consistent(surface);
  Image im = grey_image(surface.width, surface.height);
  for (std::size_t c = 0; c < surface.size(); ++c) im.pixels[c] = unit_to_byte(surface.depth_m[c] / depth_max_m);
  return im;
}

Image render_occupancy(const SurfaceMap& surface) {
  require_consistent(surface);
  Image im = grey_image(surface.width, surface.height);
  // 0.5 maps to 128 (mid grey): P * 256 clipped to 255.
  for (std::size_t c = 0; c < surface.size(); ++c) {
    const double p = std::isnan(surface.probability[c]) ? 0.0 : surface.probability[c];
    im.pixels[c] = static_cast<std::uint8_t>(std::min(255.0, std::max(0.0, std::floor(p * 256.0))));
  }
  return im;
}

Image render_improvement(const ImprovementMap& map) {
  require_shape("improvement map", map.shape());
  const std::size_t n = map.value.size();
  Image im;
  im.width = map.width;
  im.height = map.height;
  im.channels = 3;
  im.pixels.resize(n * 3);
  for (std::size_t c = 0; c < n; ++c) {
    const auto rgb = improvement_colour(map.value[c]);
    std::copy(rgb.begin(), rgb.end(), im.pixels.begin() + static_cast<std::ptrdiff_t>(3 * c));
  }
  return im;
}

Image render_improvement_legend() {
  // Bar from -0.4 to 0.4 at 4 px per 0.01, ticks and labels every 0.1.
  constexpr int kMargin = 24, kPixelsPerTenth = 40, kTenths = 8, kBarTop = 8, kBarHeight = 24, kScale = 2;
  Image im;
  im.width = 2 * kMargin + kTenths * kPixelsPerTenth + 1;
  im.height = kBarTop + kBarHeight + 6 + 5 * kScale + 8;
  im.channels = 3;
  im.pixels.assign(static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height) * 3, 255);
  for (int x = 0; x <= kTenths * kPixelsPerTenth; ++x) {
    const float value = -0.4f + 0.1f * static_cast<float>(x) / kPixelsPerTenth;
    fill(im, kMargin + x, kBarTop, 1, kBarHeight, improvement_colour(value));
  }
  for (int tick = 0; tick <= kTenths; ++tick) {
    const int x = kMargin + tick * kPixelsPerTenth;
    fill(im, x, kBarTop + kBarHeight, 1, 4, {0, 0, 0});
    const int tenths = tick - kTenths / 2;
    const std::string label = tenths == 0 ? "0" : (tenths < 0 ? "-0." : "0.") + std::to_string(std::abs(tenths));
    draw_text(im, label, x, kBarTop + kBarHeight + 6, kScale);
  }
  return im;
}

Image render_overlay(const ImprovementMap& map, const Image& colour, double improvement_weight) {
  detail::require_parameter(improvement_weight >= 0 && improvement_weight <= 1, "improvement_weight",
                            improvement_weight, "in [0, 1]");
  if (colour.channels != 3 || colour.pixels.size() % 3 != 0)
    throw InvalidInput("overlay: colour image of " + std::to_string(colour.channels) + " channels in " +
                       std::to_string(colour.pixels.size()) + " bytes is not RGB");
  const std::size_t colour_pixels = colour.pixels.size() / 3;
  require_shape("overlay: colour image", ColumnShape::of_arrays(colour.width, colour.height, {colour_pixels}),
                "the improvement map", map.shape());
  Image out = render_improvement(map);
  for (std::size_t i = 0; i < out.pixels.size(); ++i)
    out.pixels[i] = static_cast<std::uint8_t>(std::lround(improvement_weight * out.pixels[i] +
                                                          (1.0 - improvement_weight) * colour.pixels[i]));
  return out;
}

Image render_curve(const std::vector<double>& x, const std::vector<double>& y, int width, int height) {
  detail::require_parameter(width >= 16 && height >= 16, "width x height", width * 1.0 * height, ">= 16 x 16");
  if (x.size() != y.size() || x.size() < 2)
    throw InvalidInput("render_curve: " + std::to_string(x.size()) + " x values and " + std::to_string(y.size()) +
                       " y values (need the same number, at least 2)");
  Image im;
  im.width = width;
  im.height = height;
  im.channels = 3;
  im.pixels.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3, 255);
  const auto set = [&](int px, int py, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    const std::size_t i = (static_cast<std::size_t>(py) * static_cast<std::size_t>(width) + static_cast<std::size_t>(px)) * 3;
    im.pixels[i] = r, im.pixels[i + 1] = g, im.pixels[i + 2] = b;
  };
  for (int px = 0; px < width; ++px) set(px, 0, 0, 0, 0), set(px, height - 1, 0, 0, 0);
  for (int py = 0; py < height; ++py) set(0, py, 0, 0, 0), set(width - 1, py, 0, 0, 0);
  // Plain values, not structured bindings: lambdas may not capture those before C++20 (clang refuses).
  const auto x_range = std::minmax_element(x.begin(), x.end());
  const auto y_range = std::minmax_element(y.begin(), y.end());
  // The y axis spans 0 too: scaled from its own minimum to its maximum, a gain constant to six digits
  // (293222 on every shot) filled the plot with a jagged curve of its rounding.
  const double x_lo = *x_range.first, x_hi = *x_range.second;
  const double y_lo = std::min(*y_range.first, 0.0), y_hi = std::max(*y_range.second, 0.0);
  // A margin of 4 pixels inside the frame; a constant series sits in the middle.
  const auto to_px = [&](double v) { return x_hi > x_lo ? 4 + (v - x_lo) / (x_hi - x_lo) * (width - 9) : width / 2.0; };
  const auto to_py = [&](double v) { return y_hi > y_lo ? height - 5 - (v - y_lo) / (y_hi - y_lo) * (height - 9) : height / 2.0; };
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    const double x0 = to_px(x[i]), y0 = to_py(y[i]), x1 = to_px(x[i + 1]), y1 = to_py(y[i + 1]);
    const int steps = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))));
    for (int k = 0; k <= steps; ++k) {
      const double t = static_cast<double>(k) / steps;
      set(static_cast<int>(std::lround(x0 + t * (x1 - x0))), static_cast<int>(std::lround(y0 + t * (y1 - y0))), 0, 64, 255);
    }
  }
  return im;
}

}  // namespace occ_improve
