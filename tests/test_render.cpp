// Rendering and the core PNG writer: the file's structure is decoded here independently (bitwise CRC,
// stored deflate blocks, Adler-32) and compared with the pixels.
#include "occ_improve/errors.hpp"
#include "occ_improve/render.hpp"

#include <gtest/gtest.h>

#include <limits>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

namespace occ_improve {
namespace {

std::uint32_t be32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return (std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) | (std::uint32_t{b[at + 2]} << 8) | b[at + 3];
}

std::uint32_t bitwise_crc32(const std::uint8_t* p, std::size_t n) {
  std::uint32_t crc = 0xffffffffu;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

struct Chunk {
  std::string type;
  std::vector<std::uint8_t> data;
};

// Splits a PNG into chunks, checking the signature and every CRC.
std::vector<Chunk> parse_png(const std::vector<std::uint8_t>& png) {
  const std::uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  EXPECT_TRUE(png.size() > 8 && std::equal(signature, signature + 8, png.begin()));
  std::vector<Chunk> chunks;
  std::size_t at = 8;
  while (at + 12 <= png.size()) {
    const std::uint32_t len = be32(png, at);
    Chunk c;
    c.type.assign(png.begin() + static_cast<std::ptrdiff_t>(at + 4), png.begin() + static_cast<std::ptrdiff_t>(at + 8));
    c.data.assign(png.begin() + static_cast<std::ptrdiff_t>(at + 8),
                  png.begin() + static_cast<std::ptrdiff_t>(at + 8 + len));
    EXPECT_EQ(be32(png, at + 8 + len), bitwise_crc32(png.data() + at + 4, len + 4)) << c.type;
    chunks.push_back(std::move(c));
    at += 12 + len;
  }
  EXPECT_EQ(at, png.size());
  return chunks;
}

// Inflates a zlib stream made of stored blocks only, checking headers, LEN/NLEN and Adler-32.
std::vector<std::uint8_t> inflate_stored(const std::vector<std::uint8_t>& z) {
  EXPECT_EQ((z[0] * 256 + z[1]) % 31, 0);  // zlib header check bits
  EXPECT_EQ(z[0] & 0x0f, 8);                // deflate
  std::vector<std::uint8_t> out;
  std::size_t at = 2;
  bool final_block = false;
  while (!final_block) {
    final_block = z[at] & 1;
    EXPECT_EQ((z[at] >> 1) & 3, 0);  // stored
    const unsigned len = z[at + 1] | (z[at + 2] << 8), nlen = z[at + 3] | (z[at + 4] << 8);
    EXPECT_EQ(len ^ 0xffffu, nlen);
    out.insert(out.end(), z.begin() + static_cast<std::ptrdiff_t>(at + 5),
               z.begin() + static_cast<std::ptrdiff_t>(at + 5 + len));
    at += 5 + len;
  }
  std::uint32_t a = 1, b = 0;
  for (std::uint8_t v : out) a = (a + v) % 65521, b = (b + a) % 65521;
  EXPECT_EQ(be32(z, at), (b << 16) | a);
  EXPECT_EQ(at + 4, z.size());
  return out;
}

// Decodes what encode_png writes (8-bit, filter 0) back into an Image.
Image decode(const std::vector<std::uint8_t>& png) {
  const auto chunks = parse_png(png);
  EXPECT_EQ(chunks.front().type, "IHDR");
  EXPECT_EQ(chunks.back().type, "IEND");
  const auto& h = chunks.front().data;
  Image im;
  im.width = static_cast<int>(be32(h, 0));
  im.height = static_cast<int>(be32(h, 4));
  EXPECT_EQ(h[8], 8);  // bit depth
  EXPECT_TRUE(h[9] == 0 || h[9] == 2);
  EXPECT_EQ(h[10], 0);
  EXPECT_EQ(h[11], 0);
  EXPECT_EQ(h[12], 0);
  im.channels = h[9] == 0 ? 1 : 3;
  std::vector<std::uint8_t> z;
  for (const auto& c : chunks)
    if (c.type == "IDAT") z.insert(z.end(), c.data.begin(), c.data.end());
  const auto raw = inflate_stored(z);
  const std::size_t row = static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.channels);
  EXPECT_EQ(raw.size(), (row + 1) * static_cast<std::size_t>(im.height));
  for (int y = 0; y < im.height; ++y) {
    EXPECT_EQ(raw[(row + 1) * static_cast<std::size_t>(y)], 0);  // filter None
    const auto start = raw.begin() + static_cast<std::ptrdiff_t>((row + 1) * static_cast<std::size_t>(y) + 1);
    im.pixels.insert(im.pixels.end(), start, start + static_cast<std::ptrdiff_t>(row));
  }
  return im;
}

TEST(Render, PngRoundTripsGreyAndRgbAcrossSeveralDeflateBlocks) {
  for (const int channels : {1, 3}) {
    Image im;
    im.width = 301;  // 301 * 3 * 97 > 65535: several stored blocks
    im.height = 97;
    im.channels = channels;
    for (int i = 0; i < im.width * im.height * channels; ++i) im.pixels.push_back(static_cast<std::uint8_t>(i * 7 + i / 13));
    const Image back = decode(encode_png(im));
    EXPECT_EQ(back.width, im.width);
    EXPECT_EQ(back.height, im.height);
    EXPECT_EQ(back.channels, channels);
    EXPECT_EQ(back.pixels, im.pixels);
  }
}

TEST(Render, WritePngWritesTheEncodedBytesAndReportsErrors) {
  Image im;
  im.width = 2;
  im.height = 2;
  im.pixels = {0, 64, 128, 255};
  const std::string path = ::testing::TempDir() + "occ_improve_render_test.png";
  write_png(path, im);
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(bytes, encode_png(im));
  std::remove(path.c_str());
  EXPECT_THROW(write_png("/nonexistent-dir/x.png", im), IoError);
  im.pixels.pop_back();
  EXPECT_THROW(encode_png(im), InvalidInput);
}

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
  EXPECT_NO_THROW(encode_png(legend));
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
  EXPECT_THROW(render_curve({0}, {0}), InvalidInput);
  EXPECT_THROW(render_curve({0, 1}, {0}), InvalidInput);
  EXPECT_THROW(render_curve({0, 1}, {0, 1}, 8, 8), InvalidParameter);
}

}  // namespace
}  // namespace occ_improve
