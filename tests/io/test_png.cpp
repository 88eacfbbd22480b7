// The PNG writer of occ_improve::io: what it encodes is decoded here through libpng's own reader (the
// simplified png_image API, a path the writer does not use) and compared pixel for pixel.
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;

// The image as libpng reads it back, in the file's own format, which must be 8-bit grey or RGB as written.
Image decode(const std::vector<std::uint8_t>& png) {
  png_image file{};
  file.version = PNG_IMAGE_VERSION;
  Image im;
  if (!png_image_begin_read_from_memory(&file, png.data(), png.size())) {
    ADD_FAILURE() << "libpng cannot read the PNG: " << file.message;
    return im;
  }
  EXPECT_TRUE(file.format == PNG_FORMAT_GRAY || file.format == PNG_FORMAT_RGB) << "format " << file.format;
  im.width = static_cast<int>(file.width);
  im.height = static_cast<int>(file.height);
  im.channels = static_cast<int>(PNG_IMAGE_PIXEL_CHANNELS(file.format));
  im.pixels.resize(PNG_IMAGE_SIZE(file));
  EXPECT_TRUE(png_image_finish_read(&file, nullptr, im.pixels.data(), 0, nullptr)) << file.message;
  png_image_free(&file);
  return im;
}

Image pattern(int width, int height, int channels) {
  Image im;
  im.width = width;
  im.height = height;
  im.channels = channels;
  for (int i = 0; i < width * height * channels; ++i) im.pixels.push_back(static_cast<std::uint8_t>(i * 7 + i / 13));
  return im;
}

// The size of the PNG the core wrote before libpng: one stored (uncompressed) deflate block per 65535
// bytes of filter-byte-prefixed rows. Signature 8 + IHDR 25 + IDAT (12 + zlib header 2 + 5 per block +
// data + Adler-32 4) + IEND 12.
std::size_t stored_png_size(const Image& im) {
  const std::size_t raw = static_cast<std::size_t>(im.height) *
                          (static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.channels) + 1);
  const std::size_t blocks = (raw + 65534) / 65535;
  return 8 + 25 + 12 + 2 + 5 * blocks + raw + 4 + 12;
}

std::vector<std::uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Png, GreyAndRgbRoundTripExactlyAtEveryLevel) {
  for (const int channels : {1, 3})
    for (const int level : {0, 6, 9}) {
      const Image im = pattern(301, 97, channels);
      const Image back = decode(encode_png(im, level));
      EXPECT_EQ(back.width, im.width);
      EXPECT_EQ(back.height, im.height);
      EXPECT_EQ(back.channels, channels);
      EXPECT_EQ(back.pixels, im.pixels) << channels << " channels, level " << level;
    }
}

// A 16-bit grey PNG as libpng's classic reader gives it back (big-endian samples swapped to host order).
struct MemoryReader {
  const std::vector<std::uint8_t>* bytes;
  std::size_t at = 0;
};
void read_from_memory(png_structp png, png_bytep out, png_size_t length) {
  auto* m = static_cast<MemoryReader*>(png_get_io_ptr(png));
  if (m->at + length > m->bytes->size()) png_error(png, "read past the end");
  std::copy(m->bytes->begin() + static_cast<std::ptrdiff_t>(m->at),
            m->bytes->begin() + static_cast<std::ptrdiff_t>(m->at + length), out);
  m->at += length;
}
Image16 decode16(const std::vector<std::uint8_t>& bytes) {
  Image16 im;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  MemoryReader reader{&bytes};
  if (setjmp(png_jmpbuf(png))) {
    ADD_FAILURE() << "libpng cannot read the 16-bit PNG";
    png_destroy_read_struct(&png, &info, nullptr);
    return im;
  }
  png_set_read_fn(png, &reader, &read_from_memory);
  png_read_png(png, info, PNG_TRANSFORM_SWAP_ENDIAN, nullptr);
  EXPECT_EQ(png_get_bit_depth(png, info), 16);
  EXPECT_EQ(png_get_color_type(png, info), PNG_COLOR_TYPE_GRAY);
  im.width = static_cast<int>(png_get_image_width(png, info));
  im.height = static_cast<int>(png_get_image_height(png, info));
  png_bytepp rows = png_get_rows(png, info);
  for (int y = 0; y < im.height; ++y) {
    const auto* row = reinterpret_cast<const std::uint16_t*>(rows[y]);
    im.pixels.insert(im.pixels.end(), row, row + im.width);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return im;
}

TEST(Png, SixteenBitGreyRoundTripsEveryValue) {
  Image16 im;
  im.width = 257;
  im.height = 255;  // 65535 values: every 16-bit value but one, 0 and 65535 included
  for (int i = 0; i < im.width * im.height; ++i) im.pixels.push_back(static_cast<std::uint16_t>(i * 65535L / (im.width * im.height - 1)));
  for (const int level : {0, 6}) {
    const Image16 back = decode16(encode_png(im, level));
    EXPECT_EQ(back.width, im.width);
    EXPECT_EQ(back.height, im.height);
    EXPECT_EQ(back.pixels, im.pixels) << "level " << level;
  }
  im.pixels.pop_back();
  EXPECT_THROW(encode_png(im), InvalidInput);
}

TEST(Png, RefusesInconsistentImagesAndLevels) {
  Image im = pattern(2, 2, 1);
  EXPECT_THROW(encode_png(im, -1), InvalidParameter);
  EXPECT_THROW(encode_png(im, 10), InvalidParameter);
  im.pixels.pop_back();
  EXPECT_THROW(encode_png(im), InvalidInput);
  im = pattern(2, 2, 2);  // grey + alpha is not written
  EXPECT_THROW(encode_png(im), InvalidInput);
  im = pattern(0, 2, 3);
  EXPECT_THROW(encode_png(im), InvalidInput);
}

TEST(Png, WritePngWritesTheEncodedBytesAtomicallyAndReportsErrors) {
  const fs::path folder = fs::temp_directory_path() / ("occ_png_test_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  const std::string path = (folder / "x.png").string();
  const Image im = pattern(2, 2, 1);
  write_png(path, im);
  EXPECT_EQ(read_bytes(path), encode_png(im));
  Image bad = im;
  bad.pixels.pop_back();
  EXPECT_THROW(write_png(path, bad), InvalidInput);
  EXPECT_EQ(read_bytes(path), encode_png(im));  // the earlier file is left as it was
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 1);  // no temporary left
  fs::remove_all(folder);
  EXPECT_THROW(write_png("/nonexistent-dir/x.png", im), IoError);
}

// An 8-bit grey region-of-interest mask compresses ~600-fold (a square on black: ~500 bytes for 640 x 480);
// the size check took every PNG pixel for 2 bytes and refused it as "more than the file can hold".
TEST(Png, CompactEightBitMaskIsRead) {
  Image im;
  im.width = 640;
  im.height = 480;
  im.pixels.assign(640 * 480, 0);
  for (int y = 100; y < 200; ++y)
    for (int x = 300; x < 400; ++x) im.pixels[static_cast<std::size_t>(y) * 640 + static_cast<std::size_t>(x)] = 255;
  const fs::path path = fs::temp_directory_path() / ("occ_png_mask_" + std::to_string(::getpid()) + ".png");
  write_png(path.string(), im);
  ASSERT_LT(fs::file_size(path) * 1032 / 2, 640u * 480u) << "the file must be small enough to have been refused";
  const PixelMask mask = read_mask_png(path.string());
  fs::remove(path);
  ASSERT_EQ(mask.width, 640);
  ASSERT_EQ(mask.height, 480);
  std::size_t valid = 0;
  for (const auto v : mask.valid) valid += v != 0;
  EXPECT_EQ(valid, 100u * 100u);
  EXPECT_TRUE(mask.valid[150 * 640 + 350]);
  EXPECT_FALSE(mask.valid[150 * 640 + 250]);
}

// The target: a 640 x 480 improvement image at most a third of the stored encoding's size.
TEST(Png, ImprovementImageOfTheSampleSceneIsAtMostAThirdOfTheStoredSize) {
  const sample::SampleFrame frame = sample::generate_scene();
  Mapper mapper(kinect_v1(frame.intrinsics));
  mapper.insert(PointSpan::from(frame.points()));
  const Image im = render_improvement(mapper.improvement());
  ASSERT_EQ(im.width, 640);
  ASSERT_EQ(im.height, 480);
  const std::size_t stored = stored_png_size(im), compressed = encode_png(im).size();
  std::printf("640 x 480 improvement image of the sample scene: %zu bytes stored (before libpng), %zu bytes at "
              "zlib level 6 (%.1f %%)\n", stored, compressed, 100.0 * compressed / stored);
  EXPECT_LE(compressed, stored / 3);
}

}  // namespace
}  // namespace occ_improve
