// The other frame formats every tool reads through load_frame / expand_input: PCL grabbers' 16-bit TIFF
// depth (with the registered RGB TIFF beside it), PLY clouds, and the poses that come with frames
// (7-Scenes .pose.txt beside a depth image, a PCD's or PLY's VIEWPOINT).
#include "occ_improve/pcl/frame_io.hpp"
#include "../../pcl_tools/src/header_text.hpp"  // internal: not installed, tested here directly
#include "occ_improve/cancel.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/tiff_image.hpp"  // the deprecated path still compiles (docs/LAYOUT.md)
#include "support/temp_folder.hpp"
#include "support/file_bytes.hpp"
#include "support/test_data.hpp"

#include <gtest/gtest.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <future>
#include <memory>
#include <stdexcept>
#include <thread>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;

const char* const kGrabberTiff = "kinect/pcl_test/grabber_sequences/tiff";
const char* const kGrabberFrame = "frame_20121214T142255.814212";

PinholeIntrinsics grabber_intrinsics() {  // the pclzf folder's calibration XML
  PinholeIntrinsics k;
  k.fx = k.fy = 525;
  k.cx = 320;
  k.cy = 240;
  return k;
}

using test::read_bytes;
using test::write_bytes;

// ---------------------------------------------------------------------------------------------------
// TIFF

TEST(FrameIoTiffReal, GrabberDepthIsKinectMillimetresWithRegisteredColour) {
  OCC_REQUIRE_DATA(path, std::string(kGrabberTiff) + "/" + kGrabberFrame + "_depth.tiff");
  const DepthImage16 raw = read_depth_image16(path);
  ASSERT_EQ(raw.width, 640);
  ASSERT_EQ(raw.height, 480);
  const auto nonzero = std::count_if(raw.values.begin(), raw.values.end(), [](std::uint16_t v) { return v != 0; });
  const double share = static_cast<double>(nonzero) / static_cast<double>(raw.values.size());
  EXPECT_GT(share, 0.5);
  EXPECT_LT(share, 1.0);
  EXPECT_EQ(guess_depth_encoding(path, raw), DepthEncoding::millimetres);
  const LoadedFrame f = load_frame(path, grabber_intrinsics());
  EXPECT_EQ(f.encoding, DepthEncoding::millimetres);
  EXPECT_EQ(f.cloud.width, 640u);
  EXPECT_EQ(f.cloud.height, 480u);
  ASSERT_TRUE(f.colour);
  EXPECT_EQ(f.colour->width, 640);
  EXPECT_EQ(f.colour->height, 480);
  EXPECT_EQ(f.colour->channels, 3);
  ASSERT_EQ(f.colour->pixels.size(), 640u * 480u * 3u);
  const auto distinct = std::set<std::uint8_t>(f.colour->pixels.begin(), f.colour->pixels.end()).size();
  EXPECT_GT(distinct, 100u);  // a real photo, not a blank raster
}

// The grabber wrote each frame twice: as 16-bit depth TIFF and as an organized PCD in metres, back-projected
// with the calibration's 525 / 320 / 240. Measured: the same 271575 valid pixels, |dz| and |dx| 0 on every
// one (the PCD holds millimetres x 1e-3 as float, as we do); 10 um leaves room for float rounding only.
TEST(FrameIoTiffReal, BackProjectedTiffAgreesWithTheSameFramesPcd) {
  OCC_REQUIRE_DATA(tiff, std::string(kGrabberTiff) + "/" + kGrabberFrame + "_depth.tiff");
  OCC_REQUIRE_DATA(pcd, std::string("kinect/pcl_test/grabber_sequences/pcd/") + kGrabberFrame + ".pcd");
  const LoadedFrame a = load_frame(tiff, grabber_intrinsics());
  const LoadedFrame b = load_frame(pcd, std::nullopt);
  ASSERT_EQ(a.cloud.size(), b.cloud.size());
  std::size_t both = 0, only_one = 0;
  double max_dz = 0, max_dxy = 0;
  for (std::size_t i = 0; i < a.cloud.size(); ++i) {
    const bool va = std::isfinite(a.cloud[i].z), vb = std::isfinite(b.cloud[i].z);
    only_one += va != vb ? 1 : 0;
    if (!va || !vb) continue;
    ++both;
    max_dz = std::max(max_dz, static_cast<double>(std::abs(a.cloud[i].z - b.cloud[i].z)));
    max_dxy = std::max({max_dxy, static_cast<double>(std::abs(a.cloud[i].x - b.cloud[i].x)),
                        static_cast<double>(std::abs(a.cloud[i].y - b.cloud[i].y))});
  }
  EXPECT_GT(both, a.cloud.size() / 2);
  EXPECT_EQ(only_one, 0u) << "pixels valid in one of the two";
  EXPECT_LT(max_dz, 1e-5);
  EXPECT_LT(max_dxy, 1e-5);
}

TEST(FrameIoTiffReal, GrabberFolderExpandsToItsThreeDepthFrames) {
  OCC_REQUIRE_DATA(folder, kGrabberTiff);
  const std::vector<FrameSource> sources = expand_input(folder);
  ASSERT_EQ(sources.size(), 3u);
  for (const FrameSource& s : sources) {
    EXPECT_NE(s.path.find("_depth.tiff"), std::string::npos) << s.path;
    EXPECT_FALSE(s.intrinsics) << "the TIFF folder carries no calibration";
  }
  EXPECT_TRUE(std::is_sorted(sources.begin(), sources.end(),
                             [](const FrameSource& x, const FrameSource& y) { return x.path < y.path; }));
  EXPECT_THROW(load_frame(sources.front().path, std::nullopt), InvalidInput);
}

// ---------------------------------------------------------------------------------------------------
// PLY

pcl::PointCloud<pcl::PointXYZRGB> organized_rgb_cloud(std::uint32_t width, std::uint32_t height) {
  pcl::PointCloud<pcl::PointXYZRGB> cloud(width, height);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    auto& p = cloud[i];
    p.x = 0.01f * static_cast<float>(i % width) - 0.02f;
    p.y = 0.02f * static_cast<float>(i / width) - 0.01f;
    p.z = 1.0f + 0.125f * static_cast<float>(i);
    p.r = static_cast<std::uint8_t>(10 * i);
    p.g = static_cast<std::uint8_t>(255 - 10 * i);
    p.b = 7;
  }
  cloud[5].x = cloud[5].y = cloud[5].z = std::numeric_limits<float>::quiet_NaN();  // a pixel with no return
  return cloud;
}

class FrameIoPlyFiles : public test::TempFolderTest {};

TEST_F(FrameIoPlyFiles, OrganizedCloudRoundTripsInBinaryAndAscii) {
  const pcl::PointCloud<pcl::PointXYZRGB> cloud = organized_rgb_cloud(4, 3);
  ASSERT_EQ(pcl::io::savePLYFileBinary(file("binary.ply"), cloud), 0);
  ASSERT_EQ(pcl::io::savePLYFileASCII(file("ascii.PLY"), cloud), 0);
  for (const std::string& path : {file("binary.ply"), file("ascii.PLY")}) {
    const LoadedFrame f = load_frame(path, std::nullopt);
    ASSERT_EQ(f.cloud.width, 4u) << path;
    ASSERT_EQ(f.cloud.height, 3u) << path;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (i == 5) {
        EXPECT_FALSE(std::isfinite(f.cloud[i].z)) << path;
        continue;
      }
      EXPECT_FLOAT_EQ(f.cloud[i].x, cloud[i].x) << path << " point " << i;
      EXPECT_FLOAT_EQ(f.cloud[i].y, cloud[i].y) << path << " point " << i;
      EXPECT_FLOAT_EQ(f.cloud[i].z, cloud[i].z) << path << " point " << i;
    }
    ASSERT_TRUE(f.colour) << path;
    EXPECT_EQ(f.colour->width, 4);
    EXPECT_EQ(f.colour->height, 3);
    ASSERT_EQ(f.colour->pixels.size(), 36u);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (i == 5) continue;  // PCL's writer leaves the colour of a pixel without a point out
      EXPECT_EQ(f.colour->pixels[3 * i], cloud[i].r) << path << " pixel " << i;
      EXPECT_EQ(f.colour->pixels[3 * i + 1], cloud[i].g) << path << " pixel " << i;
      EXPECT_EQ(f.colour->pixels[3 * i + 2], cloud[i].b) << path << " pixel " << i;
    }
  }
}

TEST_F(FrameIoPlyFiles, UnorganizedXyzCloudRoundTrips) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 5; ++i) cloud.push_back(pcl::PointXYZ(0.1f * i, -0.2f * i, 2.0f + i));
  ASSERT_EQ(pcl::io::savePLYFileBinary(file("xyz.ply"), cloud), 0);
  const LoadedFrame f = load_frame(file("xyz.ply"), std::nullopt);
  EXPECT_EQ(f.cloud.width, 5u);
  EXPECT_EQ(f.cloud.height, 1u);
  ASSERT_EQ(f.cloud.size(), 5u);
  EXPECT_FLOAT_EQ(f.cloud[4].z, 6.0f);
  EXPECT_FALSE(f.colour);
}

// A PLY header with the given lines between the format line and end_header, then `body`.
std::string ply(const std::string& format, const std::string& lines, const std::string& body) {
  return "ply\nformat " + format + " 1.0\n" + lines + "end_header\n" + body;
}
const char* const kXyz = "property float x\nproperty float y\nproperty float z\n";

// Found by the ply fuzzer: PCL's conversion of a cloud of no points was undefined behaviour (PCD alike).
TEST_F(FrameIoPlyFiles, CloudsOfNoPointsLoadEmpty) {
  write_bytes(file("none.ply"), ply("ascii", std::string("element vertex 0\n") + kXyz, ""));
  EXPECT_TRUE(load_frame(file("none.ply"), std::nullopt).cloud.empty());
  write_bytes(file("none.pcd"), "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 0\n"
                                "HEIGHT 2\nPOINTS 0\nDATA ascii\n");
  const LoadedFrame f = load_frame(file("none.pcd"), std::nullopt);
  EXPECT_TRUE(f.cloud.empty());
  EXPECT_FALSE(f.colour);
}

TEST_F(FrameIoPlyFiles, MalformedPlyIsAFormatErrorNamingTheFile) {
  const std::string ok = ply("ascii", std::string("element vertex 2\n") + kXyz, "1 2 3\n4 5 6\n");
  write_bytes(file("ok.ply"), ok);
  EXPECT_EQ(load_ply_frame(file("ok.ply")).cloud.size(), 2u);  // the baseline the cases below break
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"empty", ""},
      {"not_ply", "plx\nformat ascii 1.0\nend_header\n"},
      {"no_end_header", "ply\nformat ascii 1.0\nelement vertex 1\n"},
      {"absurd_count", ply("binary_little_endian", std::string("element vertex 4294967295\n") + kXyz, "")},
      {"count_too_big", ply("binary_little_endian", std::string("element vertex 99999999999\n") + kXyz, "")},
      {"negative_count", ply("ascii", std::string("element vertex -1\n") + kXyz, "1 2 3\n")},
      {"more_than_file", ply("binary_little_endian", std::string("element vertex 1000\n") + kXyz, std::string(120, 'x'))},
      {"truncated_binary", ply("binary_little_endian", std::string("element vertex 10\n") + kXyz, std::string(100, '\0'))
                               .substr(0, 200)},
      {"truncated_ascii", ply("ascii", std::string("element vertex 3\n") + kXyz, "1 2 3\n4 5 6\n7 8")},
      {"bad_type", ply("ascii", "element vertex 1\nproperty float128 x\n", "1\n")},
      {"vertex_list", ply("ascii", std::string("element vertex 1\n") + kXyz + "property list uint uint n\n", "1 2 3 0\n")},
      {"cols_rows_mismatch", ply("ascii", std::string("obj_info num_cols 100000\nobj_info num_rows 100000\nelement vertex 2\n") + kXyz,
                                 "1 2 3\n4 5 6\n")},
      {"cols_negative", ply("ascii", std::string("obj_info num_cols -1\nobj_info num_rows 2\nelement vertex 2\n") + kXyz,
                            "1 2 3\n4 5 6\n")},
      {"rows_after_element", ply("ascii", std::string("obj_info num_cols 1\nelement vertex 2\nobj_info num_rows 2\n") + kXyz,
                                 "1 2 3\n4 5 6\n")},
      // A camera viewport resets width x height after PCL sized its buffer for 2 points.
      {"viewport_resize", ply("ascii", std::string("element vertex 2\n") + kXyz +
                                           "element camera 1\nproperty int viewportx\nproperty int viewporty\n",
                              "1 2 3\n4 5 6\n1000 1000\n")},
      // Passes the header's size check (a list may be empty), so PCL's parser is the one to refuse it.
      {"truncated_face_list", ply("binary_little_endian", std::string("element vertex 1\n") + kXyz +
                                                        "element face 2\nproperty list uchar int vertex_indices\n",
                                  std::string(12, '\0') + "\x03\x01")},
      {"no_vertices", ply("ascii", "element face 0\nproperty list uchar int vertex_indices\n", "")},
  };
  for (const auto& [name, bytes] : cases) {
    const std::string path = file(name + ".ply");
    write_bytes(path, bytes);
    const std::string message = test::format_error_of([&] { load_frame(path, std::nullopt); });
    EXPECT_NE(message.find(path), std::string::npos) << name << ": " << message;
  }
}

// PCL 1.13's ASCII PLY reader reads "1.5abc" and "foo" as NaN (the points then counted as invalid, not
// refused): every vertex line must hold one number per property, after any element before the vertices.
TEST_F(FrameIoPlyFiles, AsciiVertexValuesMustBeNumbers) {
  const std::string vertices = std::string("element vertex 2\n") + kXyz;
  const auto refusal = [&](const std::string& lines, const std::string& body) {
    write_bytes(file("values.ply"), ply("ascii", lines, body));
    return test::format_error_of([&] { load_frame(file("values.ply"), std::nullopt); });
  };
  EXPECT_NE(refusal(vertices, "1 2 3\n0.05 0.05 1.5abc\n").find("(vertex 2): '1.5abc' for property 'z' is not a number"),
            std::string::npos);
  EXPECT_NE(refusal(vertices, "foo 2 3\n4 5 6\n").find("(vertex 1): 'foo' for property 'x' is not a number"), std::string::npos);
  EXPECT_NE(refusal(vertices, "1 2 3\n4 5 6 7\n").find("(vertex 2) holds 4 values, the vertex has 3 properties"),
            std::string::npos);
  // An element before the vertices: its lines are skipped, one instance a line.
  const std::string camera_first = "element camera 1\nproperty int viewportx\n" + vertices;
  EXPECT_NE(refusal(camera_first, "640\n1 2 3\n4 5 x\n").find("(vertex 2): 'x' for property 'z'"), std::string::npos);
  write_bytes(file("numbers.ply"), ply("ascii", vertices, "1e-1 2 3\n4 5 6\n"));
  const LoadedFrame f = load_frame(file("numbers.ply"), std::nullopt);
  ASSERT_EQ(f.cloud.size(), 2u);
  EXPECT_FLOAT_EQ(f.cloud[0].x, 0.1f);
  EXPECT_FLOAT_EQ(f.cloud[1].z, 6.0f);
}

// Found by make fuzz: PCL 1.13 packs uchar red, green, blue (alpha) into one field that "red" opens, and
// aborts (an assert in PLYReader::vertexColorCallback) on a blue or alpha without the channels before it.
TEST_F(FrameIoPlyFiles, VertexColoursMustComeAsRedGreenBlue) {
  const std::string vertex = std::string("element vertex 2\n") + kXyz;
  for (const std::string colours : {"blue", "green blue", "red green", "red blue green", "alpha", "red green blue red"}) {
    std::string lines = vertex;
    std::string body = "1 2 3";
    std::istringstream names(colours);
    for (std::string name; names >> name;) {
      lines += "property uchar " + name + "\n";
      body += " 9";
    }
    const std::string path = file("colours.ply");
    write_bytes(path, ply("ascii", lines, body + "\n" + body + "\n"));
    EXPECT_NE(test::format_error_of([&] { load_frame(path, std::nullopt); }).find("vertex colour properties must come as red, green, blue"),
              std::string::npos)
        << colours;
  }
  for (const std::string colours : {"red green blue", "diffuse_red diffuse_green diffuse_blue", "red green blue alpha"}) {
    std::string lines = vertex;
    std::istringstream names(colours);
    for (std::string name; names >> name;) lines += "property uchar " + name + "\n";
    const std::string values = colours.find("alpha") != std::string::npos ? " 10 20 30 255" : " 10 20 30";
    write_bytes(file("rgb.ply"), ply("ascii", lines, "1 2 3" + values + "\n4 5 6" + values + "\n"));
    const LoadedFrame f = load_frame(file("rgb.ply"), std::nullopt);
    ASSERT_EQ(f.cloud.size(), 2u) << colours;
    EXPECT_FLOAT_EQ(f.cloud[1].z, 6.0f) << colours;
  }
}

// ---------------------------------------------------------------------------------------------------
// Poses

// A 2-point ASCII PCD with the given VIEWPOINT line.
std::string pcd_with_viewpoint(const std::string& viewpoint) {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
         "VIEWPOINT " + viewpoint + "\nPOINTS 2\nDATA ascii\n0 0 1\n0.5 0 2\n";
}

class FrameIoPoseFiles : public test::TempFolderTest {};

TEST_F(FrameIoPoseFiles, PcdViewpointIsAPoseUnlessIdentityOrTheLegacyGrabberValue) {
  for (const char* none : {"0 0 0 1 0 0 0", "0 0 0 0 1 0 0", "0 0 0 -1 0 0 0"}) {
    write_bytes(file("none.pcd"), pcd_with_viewpoint(none));
    const LoadedFrame f = load_frame(file("none.pcd"), std::nullopt);
    EXPECT_FALSE(f.viewpoint) << none;
    EXPECT_FLOAT_EQ(f.cloud[1].x, 0.5f) << "the points are as stored: " << none;
  }
  // 90 degrees about z (qw = qz = sqrt(1/2)), 1 m forward of the world origin.
  write_bytes(file("pose.pcd"), pcd_with_viewpoint("0.5 -1 2 0.70710678 0 0 0.70710678"));
  const LoadedFrame f = load_frame(file("pose.pcd"), std::nullopt);
  ASSERT_TRUE(f.viewpoint);
  EXPECT_TRUE(f.viewpoint->translation().isApprox(Eigen::Vector3d(0.5, -1, 2), 1e-6));
  EXPECT_TRUE((*f.viewpoint * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(0.5, 0, 2), 1e-6))
      << "camera x maps to world y, offset by the origin";
  EXPECT_FLOAT_EQ(f.cloud[1].x, 0.5f) << "the viewpoint is reported, not applied";
  // The legacy rotation away from the origin is a real pose: nothing says the grabber wrote it.
  write_bytes(file("moved.pcd"), pcd_with_viewpoint("1 0 0 0 1 0 0"));
  EXPECT_TRUE(load_frame(file("moved.pcd"), std::nullopt).viewpoint);
  write_bytes(file("zero_q.pcd"), pcd_with_viewpoint("0 0 0 0 0 0 0"));
  EXPECT_NE(test::format_error_of([&] { load_frame(file("zero_q.pcd"), std::nullopt); }).find("unit quaternion"), std::string::npos);
}

TEST(FrameIoPoseReal, KinectPcdsCarryNoViewpoint) {
  OCC_REQUIRE_DATA(grabber, std::string("kinect/pcl_test/grabber_sequences/pcd/") + kGrabberFrame + ".pcd");  // 0 0 0 0 1 0 0
  OCC_REQUIRE_DATA(office, "kinect/pcl_test/office1.pcd");
  EXPECT_FALSE(load_frame(grabber, std::nullopt).viewpoint);
  EXPECT_FALSE(load_frame(office, std::nullopt).viewpoint);
}

// PCL 1.13's PLYReader parses the camera element PCL's writer stores, then returns the default pose.
TEST_F(FrameIoPoseFiles, PlyGivesNoViewpoint) {
  pcl::PointCloud<pcl::PointXYZ> cloud(2, 2);
  for (auto& p : cloud) p = pcl::PointXYZ(0.1f, 0.2f, 1.5f);
  cloud.sensor_origin_ = Eigen::Vector4f(1, 2, 3, 0);
  cloud.sensor_orientation_ = Eigen::Quaternionf(Eigen::AngleAxisf(0.5f, Eigen::Vector3f(0, 1, 0)));
  ASSERT_EQ(pcl::io::savePLYFileBinary(file("posed.ply"), cloud), 0);
  EXPECT_NE(read_bytes(file("posed.ply")).find("property float view_px"), std::string::npos);
  const LoadedFrame f = load_frame(file("posed.ply"), std::nullopt);
  EXPECT_FALSE(f.viewpoint);
  EXPECT_EQ(f.cloud.height, 2u);
}

const char* const kPose150 =
    "9.9935108e-001 -2.3533077e-002 2.7267455e-002 -1.4496277e-001\n"
    "2.4040399e-002 9.9958366e-001 -1.8420193e-002 -9.5221795e-002\n"
    "-2.6821103e-002 1.9065253e-002 9.9945843e-001 1.2370843e-001\n"
    "0.0000000e+000 0.0000000e+000 0.0000000e+000 1.0000000e+000\n";

TEST_F(FrameIoPoseFiles, SevenScenesFolderGivesEachFrameItsPose) {
  write_bytes(file("camera-intrinsics.txt"), "585 0 320\n0 585 240\n0 0 1\n");
  for (const char* frame : {"frame-000150", "frame-000151", "frame-000152"}) write_bytes(file(std::string(frame) + ".depth.png"), "");
  write_bytes(file("frame-000150.pose.txt"), kPose150);
  write_bytes(file("frame-000152.pose.txt"), "1 0 0 0.25\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  const std::vector<FrameSource> sources = expand_input(folder_.string());
  ASSERT_EQ(sources.size(), 3u);
  ASSERT_TRUE(sources[0].pose);
  EXPECT_EQ(sources[0].pose_source, "frame-000150.pose.txt");
  EXPECT_NEAR(sources[0].pose->translation().x(), -0.14496277, 1e-7);
  EXPECT_FALSE(sources[1].pose) << "no pose file beside frame 151";
  EXPECT_EQ(sources[1].pose_source, "");
  ASSERT_TRUE(sources[2].pose);
  EXPECT_TRUE(sources[2].pose->translation().isApprox(Eigen::Vector3d(0.25, 0, 0)));
  for (const FrameSource& s : sources) EXPECT_TRUE(s.intrinsics) << s.path;
  // A single frame of the layout finds its pose too; a malformed one is refused naming the pose file.
  const std::vector<FrameSource> one = expand_input(file("frame-000150.depth.png"));
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].pose_source, "frame-000150.pose.txt");
  write_bytes(file("frame-000151.pose.txt"), "1 0 0\n");
  EXPECT_NE(test::format_error_of([&] { expand_input(folder_.string()); }).find("frame-000151.pose.txt"), std::string::npos);
}

TEST(FrameIoPoseReal, SevenScenesFramesComeWithTheirPoses) {
  OCC_REQUIRE_DATA(folder, "sequences/7scenes_redkitchen/frames");
  const std::vector<FrameSource> sources = expand_input(folder);
  ASSERT_EQ(sources.size(), 50u);
  for (const FrameSource& s : sources) {
    ASSERT_TRUE(s.pose) << s.path;
    EXPECT_EQ(s.pose_source, fs::path(pose_file_for(s.path)).filename().string());
  }
  // The camera moves about 0.25 m over the 50 frames (data README).
  const double travel = (sources.back().pose->translation() - sources.front().pose->translation()).norm();
  EXPECT_GT(travel, 0.1);
  EXPECT_LT(travel, 0.5);
}

TEST(FrameIo, PoseFileForSevenScenesNamesOnly) {
  EXPECT_EQ(pose_file_for("/d/frame-000150.depth.png"), "/d/frame-000150.pose.txt");
  EXPECT_EQ(pose_file_for("/d/frame_1_depth.tiff"), "");
  EXPECT_EQ(pose_file_for("/d/1_depth.png"), "");
}

}  // namespace
}  // namespace occ_improve

namespace occ_improve {
namespace {

// PCL's readers poll no stop request (an ASCII PLY of a few million points read for 4.4 s whatever
// Ctrl-C said): they run on a thread of their own while the caller polls. A read slower than the stop is
// abandoned within the poll's 50 ms (Cancelled, and pcl_read_abandoned() tells the program to end without
// destroying statics under it); one that finishes gives its blob; one that fails is a FormatError.
TEST(PclRead, AStopRequestAbandonsASlowReadWithinAPoll) {
  clear_stop_request();
  // The slow read waits for `release`; the test releases it at the end and waits for it to return, so
  // that no thread outlives the test (a leak checker would see its state).
  auto release = std::make_shared<std::promise<void>>();
  auto returned = std::make_shared<std::promise<void>>();
  std::shared_future<void> released = release->get_future().share();
  std::future<void> finished = returned->get_future();
  const auto slow = [released, returned](detail::PclRead& out) {
    released.wait_for(std::chrono::seconds(5));
    out.blob.width = 7;
    returned->set_value();
    return 0;
  };
  std::thread stopper([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    request_stop(SIGINT);
  });
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(detail::read_or_throw("slow.ply", "PLY", slow), Cancelled);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stopper.join();
  clear_stop_request();
  EXPECT_LT(seconds, 0.5);
  EXPECT_TRUE(pcl_read_abandoned());
  const detail::PclRead done = detail::read_or_throw("fast.ply", "PLY", [](detail::PclRead& out) {
    out.blob.width = 3;
    return 0;
  });
  EXPECT_EQ(done.blob.width, 3u);
  EXPECT_THROW(detail::read_or_throw("bad.ply", "PLY", [](detail::PclRead&) { return -1; }), FormatError);
  EXPECT_THROW(detail::read_or_throw("bad.ply", "PLY", [](detail::PclRead&) -> int { throw std::runtime_error("x"); }),
               FormatError);
  release->set_value();
  EXPECT_EQ(finished.wait_for(std::chrono::seconds(5)), std::future_status::ready);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // its last statements: setting done, freeing
}

}  // namespace
}  // namespace occ_improve
