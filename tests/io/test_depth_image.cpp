// The depth-image decoders of occ_improve::io (no PCL): PNG, PGM and TIFF read as 16-bit values, their
// sizes checked before any pixel buffer, every failure a typed error naming the file; the encodings.
#include "occ_improve/errors.hpp"
#include "occ_improve/io/depth_image.hpp"
#include "occ_improve/io/tiff.hpp"
#include "support/temp_folder.hpp"
#include "support/file_bytes.hpp"
#include "support/test_data.hpp"
#include "support/tiff_writer.hpp"

#include <gtest/gtest.h>
#include <tiffio.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

namespace occ_improve {
namespace {

using test::read_bytes;
using test::write_bytes;

std::vector<std::uint8_t> as_bytes(const std::vector<std::uint16_t>& values) {
  std::vector<std::uint8_t> bytes(values.size() * 2);
  std::memcpy(bytes.data(), values.data(), bytes.size());
  return bytes;
}

class DepthImageFiles : public test::TempFolderTest {
protected:
  std::string write(const std::string& name, const std::string& bytes) {
    write_bytes(file(name), bytes);
    return file(name);
  }
};

TEST_F(DepthImageFiles, MissingFilesAreIoErrors) {
  EXPECT_THROW(read_depth_image16(file("absent.png")), IoError);
  EXPECT_THROW(read_depth_image16(file("absent.pgm")), IoError);
}

TEST_F(DepthImageFiles, EmptyAndGarbageFilesAreFormatErrors) {
  EXPECT_THROW(read_depth_image16(write("empty.png", "")), FormatError);
  EXPECT_THROW(read_depth_image16(write("garbage.png", "not a png at all")), FormatError);
  EXPECT_THROW(read_depth_image16(write("bad.pgm", "P2 4 4 255\n")), FormatError);
  EXPECT_THROW(read_depth_image16(write("depth.tiff", "II*")), FormatError);
}

TEST_F(DepthImageFiles, TruncatedRealFilesAreFormatErrors) {
  OCC_REQUIRE_DATA(png, "formats/open3d_rgbd/TUM_depth.png");
  OCC_REQUIRE_DATA(pgm, "formats/open3d_rgbd/NYU_depth.pgm");
  const std::string png_bytes = read_bytes(png), pgm_bytes = read_bytes(pgm);
  EXPECT_THROW(read_depth_image16(write("cut.png", png_bytes.substr(0, png_bytes.size() / 2))), FormatError);
  EXPECT_THROW(read_depth_image16(write("cut.pgm", pgm_bytes.substr(0, pgm_bytes.size() / 2))), FormatError);
  // The intact copies still read, so the errors come from the truncation.
  EXPECT_NO_THROW(read_depth_image16(write("whole.png", png_bytes)));
  EXPECT_NO_THROW(read_depth_image16(write("whole.pgm", pgm_bytes)));
}

TEST(DepthImageReal, EncodingsAreGuessedFromTheValues) {
  OCC_REQUIRE_DATA(tum, "formats/open3d_rgbd/TUM_depth.png");
  EXPECT_EQ(guess_depth_encoding(tum, read_depth_image16(tum)), DepthEncoding::tum_5000);
  OCC_REQUIRE_DATA(sun, "formats/open3d_rgbd/SUN_depth.png");
  EXPECT_EQ(guess_depth_encoding(sun, read_depth_image16(sun)), DepthEncoding::sun_rotated_mm);
  OCC_REQUIRE_DATA(nyu, "formats/open3d_rgbd/NYU_depth.pgm");
  EXPECT_EQ(guess_depth_encoding(nyu, read_depth_image16(nyu)), DepthEncoding::kinect_disparity);
}

// The quantisation test of guess_depth_encoding, on values that are not multiples of 5 or 8: a Kinect's
// distinct depths 2.85e-3 z^2 m apart written at 5000 units per metre (TUM) are told from millimetres,
// and from a sensor whose values step by one unit.
TEST(DepthImage, TumScaleIsGuessedFromTheStepsBetweenDistinctDepths) {
  std::vector<double> levels_m{1.5};  // the Kinect's distinct depths from 1.5 m: each 2.85e-3 z^2 m beyond the last
  while (levels_m.back() < 3.0) levels_m.push_back(levels_m.back() + 2.85e-3 * levels_m.back() * levels_m.back());
  DepthImage16 tum{64, 48, {}}, fine{64, 48, {}};
  for (std::size_t i = 0; i < 64 * 48; ++i) {
    const double z_m = levels_m[i % levels_m.size()];
    tum.values.push_back(static_cast<std::uint16_t>(5000.0 * z_m) | 1);  // odd: not multiples of 5 or 8
    fine.values.push_back(static_cast<std::uint16_t>(3000 + i % 1400));  // steps of 1 unit, median 3.7 m
  }
  EXPECT_EQ(guess_depth_encoding("tum.png", tum), DepthEncoding::tum_5000);
  EXPECT_EQ(guess_depth_encoding("fine.png", fine), DepthEncoding::millimetres);
  // Such depths from 2.6 m in millimetres: their steps are the ones the millimetre rule predicts (the
  // median, 3.7 m, would be 0.74 m at TUM's scale: plausible, so the steps decide).
  std::vector<double> far_levels_m{2.6};
  while (far_levels_m.back() < 5.0) far_levels_m.push_back(far_levels_m.back() + 2.85e-3 * far_levels_m.back() * far_levels_m.back());
  DepthImage16 mm{64, 48, {}};
  for (std::size_t i = 0; i < 64 * 48; ++i)
    mm.values.push_back(static_cast<std::uint16_t>(1000.0 * far_levels_m[i % far_levels_m.size()]) | 1);
  EXPECT_EQ(guess_depth_encoding("mm.png", mm), DepthEncoding::millimetres);
}

// Millimetre images of round depths match the patterns of other encodings (multiples of 8 like SUN's
// shifted values, of 5 like TUM's, steps of a few units like TUM's quantisation) but read as what they are.
TEST(DepthImage, RoundMillimetreImagesAreGuessedAsMillimetres) {
  // A ramp down the rows, first_mm to last_mm, optionally rounded to whole centimetres.
  const auto ramp = [](int rows, int first_mm, int last_mm, bool centimetres) {
    DepthImage16 image{64, rows, {}};
    for (int row = 0; row < rows; ++row) {
      const int mm = first_mm + (last_mm - first_mm) * row / rows;
      image.values.insert(image.values.end(), 64, static_cast<std::uint16_t>(centimetres ? mm / 10 * 10 : mm));
    }
    return image;
  };
  // 5 m everywhere: multiples of 8, where SUN would read 0.625 m.
  EXPECT_EQ(guess_depth_encoding("flat.png", DepthImage16::filled(64, 48, 5000)), DepthEncoding::millimetres);
  // 2.6-4.6 m in steps of ~4 mm, what TUM's quantisation looks like near 2 m (it would read 0.5-0.9 m).
  EXPECT_EQ(guess_depth_encoding("ramp.png", ramp(480, 2600, 4600, false)), DepthEncoding::millimetres);
  // Whole centimetres: multiples of 5 (and of 10).
  EXPECT_EQ(guess_depth_encoding("centimetres.png", ramp(480, 2600, 4600, true)), DepthEncoding::millimetres);
  // 3-5 m in steps of 12.5 mm, whose TUM reading (0.6-1 m) would be plausible: its steps do not grow
  // with depth as a Kinect's do.
  EXPECT_EQ(guess_depth_encoding("far.png", ramp(160, 3000, 5000, false)), DepthEncoding::millimetres);
  // A SUN frame of a near scene (0.6-0.9 m, a Kinect's millimetres shifted by 3 bits) is still SUN.
  DepthImage16 sun{64, 48, {}};
  for (std::size_t i = 0; i < 64 * 48; ++i) sun.values.push_back(static_cast<std::uint16_t>(8 * (601 + i % 300)));
  EXPECT_EQ(guess_depth_encoding("sun.png", sun), DepthEncoding::sun_rotated_mm);
}

TEST(DepthImage, ValuesBecomeMetresThroughTheirEncoding) {
  const DepthImage16 image{4, 1, {0, 1500, 7500, 2047}};
  const std::vector<float> mm = depth_in_metres(image, DepthEncoding::millimetres);
  const std::vector<float> tum = depth_in_metres(image, DepthEncoding::tum_5000);
  const std::vector<float> nyu = depth_in_metres(image, DepthEncoding::kinect_disparity);
  ASSERT_EQ(mm.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_FLOAT_EQ(mm[i], image.values[i] / 1000.0f);
    EXPECT_FLOAT_EQ(tum[i], image.values[i] / 5000.0f);
  }
  EXPECT_FLOAT_EQ(nyu[0], 351.3f / 1092.5f);
  EXPECT_EQ(nyu[3], 0.0f);  // 2047: no return
  const DepthImage16 rotated{1, 1, {static_cast<std::uint16_t>(1500 << 3)}};  // SUN: 1500 mm rotated left by 3
  EXPECT_FLOAT_EQ(depth_in_metres(rotated, DepthEncoding::sun_rotated_mm)[0], 1.5f);
}

// One PNG chunk: length, type, data, CRC (which libpng checks).
std::string png_chunk(const std::string& type, const std::string& data) {
  std::string out;
  auto put32 = [&](std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out += static_cast<char>((v >> shift) & 0xff);
  };
  put32(static_cast<std::uint32_t>(data.size()));
  const std::string body = type + data;
  out += body;
  put32(static_cast<std::uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
  return out;
}

// A PNG claiming width x height 16-bit grey pixels, with a token of image data.
std::string png_header(std::uint32_t width, std::uint32_t height) {
  std::string ihdr;
  for (std::uint32_t v : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8) ihdr += static_cast<char>((v >> shift) & 0xff);
  ihdr += std::string("\x10\x00\x00\x00\x00", 5);  // 16 bit, grey, deflate, filter 0, no interlace
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", "x") + png_chunk("IEND", "");
}

// 23 bytes of PGM or 477 of PNG claiming 100000 x 100000 pixels took 14 GB before anything was refused.
TEST_F(DepthImageFiles, ImageDimensionsAreCheckedBeforeAnyPixelBuffer) {
  const auto refusal = [&](const std::string& name, const std::string& bytes) {
    return test::format_error_of([&] { read_depth_image16(write(name, bytes)); });
  };
  const std::string pgm_bomb = "P5 100000 100000 65535\n";
  EXPECT_NE(refusal("bomb.pgm", pgm_bomb).find("100000 x 100000 exceeds the cap"), std::string::npos);
  const std::string pgm_short = "P5 4000 4000 65535\n" + std::string(100, '\0');
  EXPECT_NE(refusal("short.pgm", pgm_short).find("more than the file can hold"), std::string::npos);
  EXPECT_NE(refusal("bomb.png", png_header(100000, 100000)).find("exceeds the cap"), std::string::npos);
  EXPECT_NE(refusal("short.png", png_header(8000, 8000)).find("more than the file can hold"), std::string::npos);
  // Small enough and consistent: the truncated data is libpng's to refuse.
  EXPECT_NE(refusal("cut.png", png_header(4, 4)).find("corrupt or truncated"), std::string::npos);
}

class DepthTiffFiles : public test::TempFolderTest {};

TEST_F(DepthTiffFiles, TruncatedRealTiffIsAFormatErrorNamingTheFile) {
  OCC_REQUIRE_DATA(path, "kinect/pcl_test/grabber_sequences/tiff/frame_20121214T142255.814212_depth.tiff");
  const std::string bytes = read_bytes(path), cut = file("cut_depth.tiff");
  write_bytes(cut, bytes.substr(0, bytes.size() / 2));
  testing::internal::CaptureStderr();
  const std::string message = test::format_error_of([&] { read_depth_image16(cut); });
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << "libtiff must not print";
  EXPECT_NE(message.find(cut), std::string::npos) << message;
}

TEST_F(DepthTiffFiles, Synthetic16BitTiffRoundTripsInAnyStripLayout) {
  const std::uint32_t width = 7, height = 5;
  std::vector<std::uint16_t> values(width * height);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = static_cast<std::uint16_t>(i * 1000 + 1);
  for (const std::uint32_t rows_per_strip : {1u, 2u, 5u})
    for (const std::uint16_t compression : {COMPRESSION_NONE, COMPRESSION_LZW, COMPRESSION_ADOBE_DEFLATE}) {
      const std::string path = file("d" + std::to_string(rows_per_strip) + "_" + std::to_string(compression) + ".tif");
      ASSERT_TRUE(test::write_tiff(path, width, height, 16, 1, as_bytes(values), rows_per_strip, compression));
      const DepthImage16 image = read_depth_image16(path);
      EXPECT_EQ(image.width, 7);
      EXPECT_EQ(image.height, 5);
      EXPECT_EQ(image.values, values) << path;
    }
}

TEST_F(DepthTiffFiles, OtherPixelFormatsAreRefusedNamingWhatTheyHold) {
  const std::string grey8 = file("grey8_depth.tiff"), rgb8 = file("rgb8_depth.tiff");
  ASSERT_TRUE(test::write_tiff(grey8, 4, 3, 8, 1, std::vector<std::uint8_t>(12, 7), 3));
  ASSERT_TRUE(test::write_tiff(rgb8, 4, 3, 8, 3, std::vector<std::uint8_t>(36, 7), 3));
  const std::string m8 = test::format_error_of([&] { read_depth_image16(grey8); });
  EXPECT_NE(m8.find(grey8), std::string::npos) << m8;
  EXPECT_NE(m8.find("8-bit samples, 1 per pixel"), std::string::npos) << m8;
  const std::string m3 = test::format_error_of([&] { read_depth_image16(rgb8); });
  EXPECT_NE(m3.find("8-bit samples, 3 per pixel"), std::string::npos) << m3;
  // The colour reader takes them; as a depth frame's colour it is used only at the depth's size.
  EXPECT_EQ(read_tiff_rgb8(rgb8).width, 4);
}

TEST_F(DepthTiffFiles, GarbageAndMissingTiffsAreTypedErrorsAndLibtiffPrintsNothing) {
  testing::internal::CaptureStderr();
  EXPECT_THROW(read_depth_image16(file("absent.tiff")), IoError);
  write_bytes(file("empty.tif"), "");
  EXPECT_THROW(read_depth_image16(file("empty.tif")), FormatError);
  write_bytes(file("header.TIFF"), std::string("II*\0\x08\0\0\0\xff\xff", 10));
  EXPECT_THROW(read_depth_image16(file("header.TIFF")), FormatError);
  write_bytes(file("mm.tif"), std::string("MM\0*garbage", 11));
  EXPECT_THROW(read_depth_image16(file("mm.tif")), FormatError);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(DepthImage, EncodingNamesRoundTrip) {
  for (const char* name : {"mm", "tum", "sun", "nyu"})
    EXPECT_STREQ(depth_encoding_name(parse_depth_encoding(name)), name);
  EXPECT_THROW(parse_depth_encoding("feet"), InvalidParameter);
}

TEST(DepthImage, PathsByExtension) {
  for (const char* p : {"a.png", "b.PGM", "c_depth.tiff", "d.TIF", "dir.x/e.Tiff"}) EXPECT_TRUE(is_depth_image_path(p)) << p;
  for (const char* p : {"a.pcd", "b.ply", "tiff", "c.tiff.txt", "dir.png/readme"}) EXPECT_FALSE(is_depth_image_path(p)) << p;
}

}  // namespace
}  // namespace occ_improve
