// Reading frames: every real format in shared/data decodes to plausible Kinect depths, the encoding is
// guessed right when not given, and broken files raise typed errors naming the file.
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"

#include "occ_improve/errors.hpp"
#include "support/test_data.hpp"
#include "support/file_bytes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
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
  static std::string read_bytes(const std::string& path) { return test::read_bytes(path); }
  // Each intrinsics file text is refused with a FormatError whose message holds its `named` part.
  void expect_intrinsics_refused(std::initializer_list<std::pair<const char*, const char*>> texts_and_named) {
    for (const auto& [text, named] : texts_and_named) {
      try {
        read_intrinsics_file(write("kbad.txt", text));
        ADD_FAILURE() << text << " was read";
      } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
      }
    }
  }
  // A w x h camera (fx = fy = 1) whose principal point is the image's centre.
  static PinholeIntrinsics centred_camera(int w, int h) {
    PinholeIntrinsics k;
    k.width = w;
    k.height = h;
    k.cx = (w - 1) / 2.0;
    k.cy = (h - 1) / 2.0;
    return k;
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
  EXPECT_THROW(read_intrinsics_file((dir_ / "absent.txt").string()), IoError);
  EXPECT_THROW(expand_input((dir_ / "absent").string()), IoError);
}

TEST_F(FrameIoFiles, EmptyAndGarbageFilesAreFormatErrors) {
  EXPECT_THROW(load_pcd_frame(write("empty.pcd", "")), FormatError);
  EXPECT_THROW(load_pcd_frame(write("garbage.pcd", "this is not a point cloud\n")), FormatError);
  EXPECT_THROW(load_frame(write("cloud.ply", "ply"), std::nullopt), FormatError);
  EXPECT_THROW(read_intrinsics_file(write("k.txt", "525 525 abc 239.5")), FormatError);
  EXPECT_THROW(read_intrinsics_file(write("k5.txt", "525 525 319.5 239.5 640")), FormatError);
  EXPECT_THROW(read_intrinsics_file(write("kneg.txt", "-525 525 319.5 239.5")), FormatError);
  // A word or a NaN is named with its place (">>" stopped at it and reported "not a number" or a short list).
  expect_intrinsics_refused({{"525 525 abc 239.5", "holds 'abc' at position 3"},
                             {"525 525 nan 239.5", "a non-finite value at position 3 ('nan')"}});
}

// A 3x3 matrix is K row by row, as Python's intrinsics_from_matrix takes it: a transposed K (MATLAB's
// convention) was read as cx = cy = 0 and a skew or another last row were taken without a word.
TEST_F(FrameIoFiles, AThreeByThreeMatrixMustBeAPinholeKRowByRow) {
  const PinholeIntrinsics k = read_intrinsics_file(write("k.txt", "585 0 320\n0 585 240\n0 0 1\n"));
  EXPECT_EQ(k.fx, 585);
  EXPECT_EQ(k.fy, 585);
  EXPECT_EQ(k.cx, 320);
  EXPECT_EQ(k.cy, 240);
  expect_intrinsics_refused({{"585 0 0 0 585 0 320 240 1", "it looks transposed"},
                             {"585 3 320 0 585 240 0 0 1", "(no skew)"},
                             {"585 0 320 0 585 240 0 0 2", "(no skew)"},
                             {"585 0 320 0 585 240 1 1 1", "(no skew)"}});
}

// Open3D writes PLY clouds with double x y z by default (a PCD may hold F 8 too): they were refused ("field 'x'
// is 1 x F 8 (TYPE SIZE), expected one F 4"), PCL's own conversion leaving them at 0. Converted to float.
TEST_F(FrameIoFiles, DoublePrecisionCoordinatesAreRead) {
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
                          "property double z\nend_header\n0.1 0.2 1.5\n-0.1 0.3 2.25\n";
  const std::string pcd = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
                          "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n0.1 0.2 1.5\n-0.1 0.3 2.25\n";
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"doubles.ply", ply}, {"doubles.pcd", pcd}}) {
    const LoadedFrame f = load_frame(write(name, text), std::nullopt);
    ASSERT_EQ(f.cloud.size(), 2u) << name;
    EXPECT_FLOAT_EQ(f.cloud[0].x, 0.1f) << name;
    EXPECT_FLOAT_EQ(f.cloud[0].y, 0.2f) << name;
    EXPECT_FLOAT_EQ(f.cloud[0].z, 1.5f) << name;
    EXPECT_FLOAT_EQ(f.cloud[1].x, -0.1f) << name;
    EXPECT_FLOAT_EQ(f.cloud[1].z, 2.25f) << name;
  }
  // Mixed precision is still refused, naming the field.
  const std::string mixed = "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty float y\n"
                            "property float z\nend_header\n0.1 0.2 1.5\n";
  EXPECT_THROW(load_frame(write("mixed.ply", mixed), std::nullopt), FormatError);
}

TEST_F(FrameIoFiles, PcdWithoutXyzIsAFormatError) {
  const std::string pcd =
      "# .PCD v0.7\nVERSION 0.7\nFIELDS intensity\nSIZE 4\nTYPE F\nCOUNT 1\nWIDTH 2\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1\n2\n";
  EXPECT_THROW(load_pcd_frame(write("intensity.pcd", pcd)), FormatError);
}

TEST_F(FrameIoFiles, TruncatedRealPcdIsAFormatError) {
  OCC_REQUIRE_DATA(pcd, "kinect/pcl_test/office1.pcd");
  const std::string pcd_bytes = read_bytes(pcd);
  EXPECT_THROW(load_pcd_frame(write("cut.pcd", pcd_bytes.substr(0, pcd_bytes.size() / 2))), FormatError);
  // The intact copy still reads, so the error comes from the truncation.
  EXPECT_NO_THROW(load_pcd_frame(write("whole.pcd", pcd_bytes)));
}

TEST_F(FrameIoFiles, AllZeroDepthImageLoadsAsAFrameWithNoValidPoint) {
  std::string pgm = "P5 4 3 65535\n";
  pgm.append(4 * 3 * 2, '\0');
  const PinholeIntrinsics k = centred_camera(4, 3);
  const LoadedFrame f = load_frame(write("zeros.pgm", pgm), k, DepthEncoding::millimetres);
  EXPECT_EQ(f.cloud.size(), 12u);
  EXPECT_EQ(stats_of(f.cloud).valid_fraction, 0.0);
}

// A PGM header may hold comments ('#' to the end of the line: GIMP and ImageMagick write one after the
// magic); a commented 16-bit PGM was refused as "not a 16-bit binary PGM (P5)".
TEST_F(FrameIoFiles, PgmHeaderCommentsAreSkipped) {
  std::string pgm = "P5\n# written by GIMP\n2 1 # width height\n65535\n";
  pgm += std::string("\x05\xdc\x07\xd0", 4);  // 1500 and 2000 mm, big-endian
  const PinholeIntrinsics k = centred_camera(2, 1);
  const LoadedFrame f = load_frame(write("commented.pgm", pgm), k, DepthEncoding::millimetres);
  ASSERT_EQ(f.cloud.size(), 2u);
  EXPECT_FLOAT_EQ(f.cloud[0].z, 1.5f);
  EXPECT_FLOAT_EQ(f.cloud[1].z, 2.0f);
  EXPECT_THROW(load_frame(write("signed.pgm", "P5 -2 1 65535\n" + std::string(4, '\0')), k, DepthEncoding::millimetres),
               FormatError);
}

// A 3x3 camera-intrinsics.txt (7-Scenes, 3DMatch) carries no image size: a folder's camera takes its
// frames' size, as a folder of a 320 x 240 camera needs (it was 640 x 480 whatever the frames).
TEST_F(FrameIoFiles, AFolderCameraWithoutASizeTakesItsFramesSize) {
  write_png((dir_ / "frame-000000.depth.png").string(), Image16{32, 24, std::vector<std::uint16_t>(32 * 24, 1500)});
  write("camera-intrinsics.txt", "26.25 0 15.5\n0 26.25 11.5\n0 0 1\n");
  const std::vector<FrameSource> sources = expand_input(dir_.string());
  ASSERT_EQ(sources.size(), 1u);
  ASSERT_TRUE(sources[0].intrinsics);
  EXPECT_EQ(sources[0].intrinsics->width, 32);
  EXPECT_EQ(sources[0].intrinsics->height, 24);
  EXPECT_DOUBLE_EQ(sources[0].intrinsics->fx, 26.25);
  const DepthSequence sequence = scan_depth_sequence(dir_.string());
  ASSERT_TRUE(sequence.intrinsics);
  EXPECT_EQ(sequence.intrinsics->width, 32);
  EXPECT_EQ(sequence.intrinsics->height, 24);
  EXPECT_EQ(load_frame(sources[0].path, sources[0].intrinsics).cloud.width, 32u);
  // A size in the file is the file's.
  write("camera-intrinsics.txt", "26.25 26.25 15.5 11.5 64 48\n");
  EXPECT_EQ(expand_input(dir_.string())[0].intrinsics->width, 64);
}

// A 7-Scenes scene folder (seq-01/, seq-02/ beside the scene's camera) is one sequence: its subfolders'
// frames in folder then name order, each with its own pose, as occ_improve_map reads such a folder.
TEST_F(FrameIoFiles, ASceneFolderIsTheSequenceOfItsSubfolders) {
  const Image16 frame{32, 24, std::vector<std::uint16_t>(32 * 24, 1500)};
  for (const char* seq : {"seq-02", "seq-01"}) {
    fs::create_directories(dir_ / seq);
    for (int i = 0; i < 2; ++i) {
      const std::string stem = (dir_ / seq / ("frame-00000" + std::to_string(i))).string();
      write_png(stem + ".depth.png", frame);
      std::ofstream(stem + ".pose.txt") << "1 0 0 " << (seq[5] - '0') << "\n0 1 0 " << i << "\n0 0 1 0\n0 0 0 1\n";
    }
  }
  write("camera-intrinsics.txt", "26.25 0 15.5\n0 26.25 11.5\n0 0 1\n");
  const DepthSequence sequence = scan_depth_sequence(dir_.string());
  ASSERT_EQ(sequence.frames.size(), 4u);
  ASSERT_TRUE(sequence.intrinsics);
  EXPECT_EQ(sequence.intrinsics->width, 32);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_NE(sequence.frames[k].depth_path.find(k < 2 ? "seq-01" : "seq-02"), std::string::npos);
    ASSERT_TRUE(sequence.frames[k].camera_to_world);
    EXPECT_EQ(sequence.frames[k].camera_to_world->translation().x(), k < 2 ? 1.0 : 2.0);
    EXPECT_EQ(sequence.frames[k].camera_to_world->translation().y(), static_cast<double>(k % 2));
  }
  // Subfolders of two cameras are not one sequence.
  std::ofstream((dir_ / "seq-02" / "camera-intrinsics.txt").string()) << "30 0 15.5\n0 30 11.5\n0 0 1\n";
  try {
    scan_depth_sequence(dir_.string());
    FAIL() << "two cameras were read as one sequence";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("seq-02"), std::string::npos) << e.what();
  }
}

// A 3 x 3 matrix says nothing of the size: a depth image beside it, whatever its name, sizes it (a
// 320 x 240 scene.png was refused against an assumed 640 x 480). A tool taking one frame refuses a folder.
TEST_F(FrameIoFiles, AnyDepthImageSizesTheCameraBesideItAndOneFrameIsNotAFolder) {
  write_png((dir_ / "scene.png").string(), Image16{32, 24, std::vector<std::uint16_t>(32 * 24, 1500)});
  write("camera-intrinsics.txt", "26.25 0 15.5\n0 26.25 11.5\n0 0 1\n");
  const FrameSource source = single_frame_source((dir_ / "scene.png").string(), "-simulate");
  ASSERT_TRUE(source.intrinsics);
  EXPECT_EQ(source.intrinsics->width, 32);
  EXPECT_EQ(source.intrinsics->height, 24);
  EXPECT_EQ(load_frame(source.path, source.intrinsics).cloud.width, 32u);
  write_png((dir_ / "frame-000000.depth.png").string(), Image16{32, 24, std::vector<std::uint16_t>(32 * 24, 1500)});
  write_png((dir_ / "frame-000001.depth.png").string(), Image16{32, 24, std::vector<std::uint16_t>(32 * 24, 1500)});
  try {
    single_frame_source(dir_.string(), "-simulate");
    FAIL() << "a folder was taken as one frame";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("folder of 2 frames"), std::string::npos) << e.what();
  }
}

TEST_F(FrameIoFiles, FolderWithoutFramesIsInvalidInput) {
  write("notes.txt", "nothing here");
  EXPECT_THROW(expand_input(dir_.string()), InvalidInput);
}

}  // namespace
}  // namespace occ_improve
