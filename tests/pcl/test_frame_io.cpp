// Reading frames: every real format in shared/data decodes to plausible Kinect depths, the encoding is
// guessed right when not given, and broken files raise typed errors naming the file.
#include "occ_improve/pcl/frame_io.hpp"

#include "occ_improve/errors.hpp"
#include "support/test_data.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;

struct DepthStats {
  double valid_fraction = 0;
  double median_z_m = 0;
};

DepthStats stats_of(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  std::vector<float> z;
  for (const auto& p : cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && p.z > 0) z.push_back(p.z);
  DepthStats s;
  if (cloud.empty() || z.empty()) return s;
  s.valid_fraction = static_cast<double>(z.size()) / static_cast<double>(cloud.size());
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
  s.median_z_m = z[z.size() / 2];
  return s;
}

void expect_plausible_kinect_frame(const LoadedFrame& f, double min_valid_fraction) {
  EXPECT_EQ(f.cloud.width, 640u);
  EXPECT_EQ(f.cloud.height, 480u);
  const DepthStats s = stats_of(f.cloud);
  EXPECT_GE(s.valid_fraction, min_valid_fraction) << f.path;
  EXPECT_LE(s.valid_fraction, 1.0) << f.path;
  EXPECT_GT(s.median_z_m, 0.5) << f.path;
  EXPECT_LT(s.median_z_m, 8.0) << f.path;
}

// A scratch folder removed at the end of each test.
class FrameIoFiles : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("occ_improve_test_frame_io_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& bytes) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  static std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  fs::path dir_;
};

TEST(FrameIoReal, KinectPcdIsOrganizedWithPlausibleDepths) {
  OCC_REQUIRE_DATA(path, "kinect/pcl_test/five_people.pcd");
  const LoadedFrame f = load_pcd_frame(path);
  expect_plausible_kinect_frame(f, 0.7);
  EXPECT_FALSE(f.intrinsics);
  OCC_REQUIRE_DATA(xyz_only, "kinect/pcl_tutorials/pairwise/capture0001.pcd");
  expect_plausible_kinect_frame(load_frame(xyz_only, std::nullopt), 0.5);
}

TEST(FrameIoReal, TumPngIsGuessedAsOneFiveThousandthMetre) {
  OCC_REQUIRE_DATA(path, "formats/open3d_rgbd/TUM_depth.png");
  const DepthImage16 raw = read_depth_image16(path);
  EXPECT_EQ(guess_depth_encoding(path, raw), DepthEncoding::tum_5000);
  const LoadedFrame f = load_frame(path, kinect_v1_intrinsics());
  EXPECT_EQ(f.encoding, DepthEncoding::tum_5000);
  expect_plausible_kinect_frame(f, 0.5);
  OCC_REQUIRE_DATA(fr2, "formats/tum_fr2/ch7/1_depth.png");
  PinholeIntrinsics k;
  k.fx = 520.9;
  k.fy = 521.0;
  k.cx = 325.1;
  k.cy = 249.7;
  const LoadedFrame g = load_frame(fr2, k);
  EXPECT_EQ(g.encoding, DepthEncoding::tum_5000);
  expect_plausible_kinect_frame(g, 0.5);
}

TEST(FrameIoReal, SunPngIsGuessedAsRotatedMillimetres) {
  OCC_REQUIRE_DATA(path, "formats/open3d_rgbd/SUN_depth.png");
  const LoadedFrame f = load_frame(path, kinect_v1_intrinsics());
  EXPECT_EQ(f.encoding, DepthEncoding::sun_rotated_mm);
  expect_plausible_kinect_frame(f, 0.5);
  // Read as plain millimetres the same file gives depths 8 times too large: the guess matters.
  EXPECT_GT(stats_of(load_frame(path, kinect_v1_intrinsics(), DepthEncoding::millimetres).cloud).median_z_m, 8.0);
}

TEST(FrameIoReal, NyuPgmIsGuessedAsRawDisparity) {
  OCC_REQUIRE_DATA(path, "formats/open3d_rgbd/NYU_depth.pgm");
  const LoadedFrame f = load_frame(path, kinect_v1_intrinsics());
  EXPECT_EQ(f.encoding, DepthEncoding::kinect_disparity);
  expect_plausible_kinect_frame(f, 0.5);
}

TEST(FrameIoReal, ThreeDMatchFolderExpandsToSortedFramesWithItsIntrinsics) {
  OCC_REQUIRE_DATA(folder, "formats/sun3d_studyroom/3dmatch");
  const std::vector<FrameSource> sources = expand_input(folder);
  ASSERT_EQ(sources.size(), 5u);
  EXPECT_TRUE(std::is_sorted(sources.begin(), sources.end(),
                             [](const FrameSource& a, const FrameSource& b) { return a.path < b.path; }));
  for (const FrameSource& s : sources) {
    ASSERT_TRUE(s.intrinsics) << s.path;
    EXPECT_NEAR(s.intrinsics->fx, 570.342205, 1e-6);
    EXPECT_EQ(s.intrinsics->cx, 320);
  }
  // A single frame of the layout finds the intrinsics one folder up.
  const std::vector<FrameSource> one = expand_input(sources.front().path);
  ASSERT_EQ(one.size(), 1u);
  ASSERT_TRUE(one.front().intrinsics);
  const LoadedFrame f = load_frame(one.front().path, one.front().intrinsics);
  EXPECT_EQ(f.encoding, DepthEncoding::millimetres);
  expect_plausible_kinect_frame(f, 0.5);
}

TEST(FrameIoReal, ImageSizeMustMatchIntrinsics) {
  OCC_REQUIRE_DATA(path, "formats/open3d_rgbd/TUM_depth.png");
  PinholeIntrinsics small;
  small.width = 320;
  small.height = 240;
  EXPECT_THROW(load_frame(path, small), InvalidInput);
  EXPECT_THROW(load_frame(path, std::nullopt), InvalidInput);  // no intrinsics at all
}

TEST_F(FrameIoFiles, MissingFilesAreIoErrors) {
  EXPECT_THROW(load_pcd_frame((dir_ / "absent.pcd").string()), IoError);
  EXPECT_THROW(read_depth_image16((dir_ / "absent.png").string()), IoError);
  EXPECT_THROW(read_intrinsics_file((dir_ / "absent.txt").string()), IoError);
  EXPECT_THROW(expand_input((dir_ / "absent").string()), IoError);
}

TEST_F(FrameIoFiles, EmptyAndGarbageFilesAreFormatErrors) {
  EXPECT_THROW(load_pcd_frame(write("empty.pcd", "")), FormatError);
  EXPECT_THROW(load_pcd_frame(write("garbage.pcd", "this is not a point cloud\n")), FormatError);
  EXPECT_THROW(read_depth_image16(write("empty.png", "")), FormatError);
  EXPECT_THROW(read_depth_image16(write("garbage.png", "not a png at all")), FormatError);
  EXPECT_THROW(read_depth_image16(write("bad.pgm", "P2 4 4 255\n")), FormatError);
  EXPECT_THROW(read_depth_image16(write("depth.tiff", "II*")), FormatError);
  EXPECT_THROW(load_frame(write("cloud.ply", "ply"), std::nullopt), FormatError);
  EXPECT_THROW(read_intrinsics_file(write("k.txt", "525 525 abc 239.5")), FormatError);
  EXPECT_THROW(read_intrinsics_file(write("k5.txt", "525 525 319.5 239.5 640")), FormatError);
  EXPECT_THROW(read_intrinsics_file(write("kneg.txt", "-525 525 319.5 239.5")), FormatError);
}

TEST_F(FrameIoFiles, PcdWithoutXyzIsAFormatError) {
  const std::string pcd =
      "# .PCD v0.7\nVERSION 0.7\nFIELDS intensity\nSIZE 4\nTYPE F\nCOUNT 1\nWIDTH 2\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1\n2\n";
  EXPECT_THROW(load_pcd_frame(write("intensity.pcd", pcd)), FormatError);
}

TEST_F(FrameIoFiles, TruncatedRealFilesAreFormatErrors) {
  OCC_REQUIRE_DATA(pcd, "kinect/pcl_test/office1.pcd");
  OCC_REQUIRE_DATA(png, "formats/open3d_rgbd/TUM_depth.png");
  OCC_REQUIRE_DATA(pgm, "formats/open3d_rgbd/NYU_depth.pgm");
  const std::string pcd_bytes = read_bytes(pcd), png_bytes = read_bytes(png), pgm_bytes = read_bytes(pgm);
  EXPECT_THROW(load_pcd_frame(write("cut.pcd", pcd_bytes.substr(0, pcd_bytes.size() / 2))), FormatError);
  EXPECT_THROW(read_depth_image16(write("cut.png", png_bytes.substr(0, png_bytes.size() / 2))), FormatError);
  EXPECT_THROW(read_depth_image16(write("cut.pgm", pgm_bytes.substr(0, pgm_bytes.size() / 2))), FormatError);
  // The intact copies still read, so the errors come from the truncation.
  EXPECT_NO_THROW(read_depth_image16(write("whole.png", png_bytes)));
}

TEST_F(FrameIoFiles, AllZeroDepthImageLoadsAsAFrameWithNoValidPoint) {
  std::string pgm = "P5 4 3 65535\n";
  pgm.append(4 * 3 * 2, '\0');
  PinholeIntrinsics k;
  k.width = 4;
  k.height = 3;
  k.cx = 1.5;
  k.cy = 1;
  const LoadedFrame f = load_frame(write("zeros.pgm", pgm), k, DepthEncoding::millimetres);
  EXPECT_EQ(f.cloud.size(), 12u);
  EXPECT_EQ(stats_of(f.cloud).valid_fraction, 0.0);
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
TEST_F(FrameIoFiles, ImageDimensionsAreCheckedBeforeAnyPixelBuffer) {
  auto message_of = [&](const std::string& name, const std::string& bytes) -> std::string {
    try {
      read_depth_image16(write(name, bytes));
    } catch (const FormatError& e) {
      return e.what();
    }
    return "no FormatError";
  };
  const std::string pgm_bomb = "P5 100000 100000 65535\n";
  EXPECT_NE(message_of("bomb.pgm", pgm_bomb).find("100000 x 100000 exceeds the cap"), std::string::npos);
  const std::string pgm_short = "P5 4000 4000 65535\n" + std::string(100, '\0');
  EXPECT_NE(message_of("short.pgm", pgm_short).find("more than the file can hold"), std::string::npos);
  EXPECT_NE(message_of("bomb.png", png_header(100000, 100000)).find("exceeds the cap"), std::string::npos);
  EXPECT_NE(message_of("short.png", png_header(8000, 8000)).find("more than the file can hold"), std::string::npos);
  // Small enough and consistent: the truncated data is libpng's to refuse.
  EXPECT_NE(message_of("cut.png", png_header(4, 4)).find("corrupt or truncated"), std::string::npos);
}

TEST_F(FrameIoFiles, FolderWithoutFramesIsInvalidInput) {
  write("notes.txt", "nothing here");
  EXPECT_THROW(expand_input(dir_.string()), InvalidInput);
}

TEST(FrameIo, EncodingNamesRoundTrip) {
  for (const char* name : {"mm", "tum", "sun", "nyu"})
    EXPECT_STREQ(depth_encoding_name(parse_depth_encoding(name)), name);
  EXPECT_THROW(parse_depth_encoding("feet"), InvalidParameter);
}

}  // namespace
}  // namespace occ_improve
