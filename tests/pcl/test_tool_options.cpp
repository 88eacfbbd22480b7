#include "occ_improve/tools/frame_fusion.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/plan_flags.hpp"
#include "occ_improve/tools/progress.hpp"
#include "occ_improve/tools/segmentation_flags.hpp"
#include "occ_improve/tools/signals.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_mask.hpp"
#include "occ_improve/tools/tool_options.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "support/command_line_args.hpp"
#include "support/test_data.hpp"

#include <Eigen/Geometry>
#include <pcl/io/pcd_io.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <functional>
#include <fstream>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace occ_improve {
namespace {

// argv for the parser: "tool" then the given arguments.
using test::Args;

// A tool taking the shared sensor, camera and output flags, -k and -sample, and frame inputs.
const ToolFlags kTool{"tool",
                      {"[options] INPUT..."},
                      "",
                      joined({sensor_flag_names(), camera_flag_names(), output_folder_flag_names(), {"-k", "-sample", "-no_poses"}}),
                      {},
                      {},
                      "  INPUT\n"};

ToolOptions parse(std::initializer_list<std::string> args) {
  Args a(args);
  return parse_tool_options(parse_command_line(kTool, a.argc(), a.argv.data()));
}

// The message of the InvalidParameter the arguments raise ("" when none).
std::string error_of(std::initializer_list<std::string> args) {
  return test::invalid_parameter_of([&] { parse(args); });
}

TEST(ToolOptions, DefaultsAreThePixelNativePresetClampedWithNoInputs) {
  const ToolOptions t = parse({});
  EXPECT_EQ(t.preset_name, "kinect_v1");
  EXPECT_EQ(t.preset.geometry.angular_binning, AngularBinning::pinhole);
  EXPECT_EQ(t.preset.geometry.depth_bins, kinect_v1().geometry.depth_bins);
  EXPECT_EQ(t.preset.model.sigma_depth_per_m2, kinect_v1().model.sigma_depth_per_m2);
  EXPECT_TRUE(t.preset_needs_camera());
  EXPECT_EQ(t.grid.mode, UpdateMode::clamped);
  EXPECT_EQ(t.grid.probability_min, GridOptions{}.probability_min);
  EXPECT_FALSE(t.intrinsics);
  EXPECT_FALSE(t.depth_encoding);
  EXPECT_TRUE(t.inputs.empty());
  EXPECT_EQ(t.top_k, 10);
}

TEST(ToolOptions, InputsAreThePositionalArgumentsInOrderNotFlagValues) {
  const ToolOptions t = parse({"b.pcd", "-o", "out", "-sample", "a.png", "-k", "3", "c_folder"});
  EXPECT_EQ(t.inputs, (std::vector<std::string>{"b.pcd", "a.png", "c_folder"}));
  EXPECT_EQ(t.top_k, 3);
}

TEST(ToolOptions, OverridesReachThePreset) {
  const ToolOptions t = parse({"-preset", "kinect_v1_paper", "-sigma_depth", "0.01", "-sigma_depth_quadratic", "0.002", "-sigma_angle", "0.001",
                               "-support_k", "3", "-depth_bins", "256", "-depth_max", "4", "-fov", "60,40"});
  EXPECT_DOUBLE_EQ(t.preset.model.sigma_depth_m, 0.01);
  EXPECT_DOUBLE_EQ(t.preset.model.sigma_depth_per_m2, 0.002);
  EXPECT_DOUBLE_EQ(t.preset.model.sigma_azimuth_rad, 0.001);
  EXPECT_DOUBLE_EQ(t.preset.model.sigma_elevation_rad, 0.001);
  EXPECT_DOUBLE_EQ(t.preset.model.support_k, 3);
  EXPECT_EQ(t.preset.geometry.depth_bins, 256);
  EXPECT_DOUBLE_EQ(t.preset.geometry.depth_max_m, 4);
  EXPECT_NEAR(t.preset.geometry.azimuth_max_rad - t.preset.geometry.azimuth_min_rad, 60 * M_PI / 180, 1e-12);
  EXPECT_NEAR(t.preset.geometry.elevation_max_rad, 20 * M_PI / 180, 1e-12);
  // On the pixel-native grid the angle becomes pixels, and the field of view is the image's.
  const ToolOptions pixels = parse({"-sigma_angle", "0.001"});
  EXPECT_NEAR(pixels.preset.model.sigma_u_px, std::tan(0.001) * 525, 1e-9);
  EXPECT_NE(error_of({"-fov", "60,40"}).find("-fov applies to spherical grids"), std::string::npos);
}

TEST(ToolOptions, ModeClampAndEncoding) {
  const ToolOptions exact = parse({"-mode", "exact"});
  EXPECT_EQ(exact.grid.mode, UpdateMode::exact);
  const ToolOptions octomap = parse({"-clamp", "octomap"});
  EXPECT_EQ(octomap.grid.mode, UpdateMode::clamped);
  EXPECT_EQ(octomap.grid.probability_min, GridOptions::octomap_clamping().probability_min);
  EXPECT_EQ(octomap.grid.probability_max, GridOptions::octomap_clamping().probability_max);
  EXPECT_EQ(parse({"-depth_encoding", "tum"}).depth_encoding, DepthEncoding::tum_5000);
  EXPECT_EQ(parse({"-depth_encoding", "nyu"}).depth_encoding, DepthEncoding::kinect_disparity);
}

TEST(ToolOptions, IntrinsicsBuildTheCameraPreset) {
  const ToolOptions t = parse({"-preset", "kinect_v1", "-intrinsics", "570,571,320,240,320,240"});
  ASSERT_TRUE(t.intrinsics);
  EXPECT_EQ(t.intrinsics->fx, 570);
  EXPECT_EQ(t.intrinsics->width, 320);
  EXPECT_EQ(t.preset.geometry.azimuth_bins, 320);
  EXPECT_EQ(t.preset.geometry.elevation_bins, 240);
  ASSERT_TRUE(t.preset.camera);
  EXPECT_EQ(t.preset.camera->fy, 571);
  // The paper preset keeps its own geometry whatever the camera.
  const ToolOptions paper = parse({"-preset", "kinect_v1_paper", "-intrinsics", "570,571,320,240,320,240"});
  EXPECT_EQ(paper.preset.geometry.azimuth_bins, 640);
}

TEST(ToolOptions, PresetForCameraUsesAFoundCameraUnlessOneWasGiven) {
  PinholeIntrinsics found;
  found.fx = found.fy = 585;
  found.width = 320;
  found.height = 240;
  found.cx = 160;
  found.cy = 120;
  const ToolOptions t = parse({"-preset", "kinect_v1", "-depth_bins", "128"});
  const SensorPreset p = t.preset_for_camera(found);
  EXPECT_EQ(p.geometry.azimuth_bins, 320);
  EXPECT_EQ(p.geometry.depth_bins, 128);  // overrides re-applied
  const ToolOptions given = parse({"-preset", "kinect_v1", "-intrinsics", "525,525,319.5,239.5"});
  EXPECT_EQ(given.preset_for_camera(found).geometry.azimuth_bins, 640);
  EXPECT_EQ(parse({"-preset", "kinect_v1_paper"}).preset_for_camera(found).geometry.azimuth_bins, 640);
  // The spherical camera preset keeps its binning for the found camera.
  const SensorPreset spherical = parse({"-preset", "kinect_v1_spherical"}).preset_for_camera(found);
  EXPECT_EQ(spherical.geometry.angular_binning, AngularBinning::spherical);
  EXPECT_EQ(spherical.geometry.azimuth_bins, 320);
}

TEST(ToolOptions, IntrinsicsFile) {
  const auto path = std::filesystem::temp_directory_path() / "occ_improve_test_tool_options_intrinsics.txt";
  {
    std::ofstream(path) << "580 581 321 241\n";
  }
  const ToolOptions t = parse({"-intrinsics_file", path.string()});
  ASSERT_TRUE(t.intrinsics);
  EXPECT_EQ(t.intrinsics->fy, 581);
  EXPECT_EQ(t.intrinsics->cy, 241);
  std::filesystem::remove(path);
  EXPECT_THROW(parse({"-intrinsics_file", path.string()}), IoError);
}

TEST(ToolOptions, BadValuesNameTheFlag) {
  EXPECT_NE(error_of({"-preset", "kinect_v9"}).find("-preset"), std::string::npos);
  EXPECT_NE(error_of({"-k", "0"}).find("-k"), std::string::npos);
  EXPECT_NE(error_of({"-k", "-3"}).find("-k"), std::string::npos);
  EXPECT_NE(error_of({"-k", "three"}).find("-k"), std::string::npos);
  EXPECT_NE(error_of({"-sigma_depth", "abc"}).find("-sigma_depth"), std::string::npos);
  EXPECT_NE(error_of({"-sigma_depth", "-1"}).find("-sigma_depth"), std::string::npos);
  EXPECT_NE(error_of({"-sigma_angle", "0"}).find("-sigma_angle"), std::string::npos);
  EXPECT_NE(error_of({"-depth_bins", "0"}).find("-depth_bins"), std::string::npos);
  EXPECT_NE(error_of({"-depth_bins", "2.5"}).find("-depth_bins"), std::string::npos);
  EXPECT_NE(error_of({"-depth_max", "nan"}).find("-depth_max"), std::string::npos);
  EXPECT_NE(error_of({"-fov", "57"}).find("-fov"), std::string::npos);
  EXPECT_NE(error_of({"-fov", "57,400"}).find("-fov"), std::string::npos);
  EXPECT_NE(error_of({"-mode", "fast"}).find("-mode"), std::string::npos);
  EXPECT_NE(error_of({"-clamp", "tight"}).find("-clamp"), std::string::npos);
  EXPECT_NE(error_of({"-depth_encoding", "inches"}).find("-depth_encoding"), std::string::npos);
  EXPECT_NE(error_of({"-intrinsics", "525,525,319.5"}).find("-intrinsics"), std::string::npos);
  EXPECT_NE(error_of({"-intrinsics", "-525,525,319.5,239.5"}).find("-intrinsics"), std::string::npos);
  EXPECT_NE(error_of({"-intrinsics", "525,525,319.5,239.5,640.5,480"}).find("-intrinsics"), std::string::npos);
  EXPECT_NE(error_of({"-frobnicate"}).find("-frobnicate"), std::string::npos);
  EXPECT_NE(error_of({"-preset"}).find("-preset"), std::string::npos);  // value missing
}

TEST(ToolOptions, FlagsTheToolDoesNotDeclareAreUnknown) {
  const ToolFlags without_k{"tool", {""}, "", sensor_flag_names(), {}, {}, "  INPUT\n"};
  Args a({"-k", "3"});
  try {
    parse_command_line(without_k, a.argc(), a.argv.data());
    FAIL() << "-k is not declared";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("unknown option -k"), std::string::npos) << e.what();
  }
}

TEST(ToolOptions, UsageListsTheCommonFlagsWithTheirDefaults) {
  std::string usage = usage_text(kTool, "tool");
  // Wrapped lines joined, so that a default split over two lines is found.
  for (std::size_t at; (at = usage.find("\n" + std::string(28, ' '))) != std::string::npos;) usage.replace(at, 29, " ");
  for (const char* flag : {"-preset", "-sigma_depth", "-sigma_angle", "-depth_bins", "-depth_max", "-fov", "-mode",
                           "-clamp", "-intrinsics", "-intrinsics_file", "-depth_encoding", "-k"})
    EXPECT_NE(usage.find(std::string("  ") + flag + " "), std::string::npos) << flag;
  EXPECT_NE(usage.find("(default kinect_v1)"), std::string::npos);
  EXPECT_NE(usage.find("(default clamped)"), std::string::npos);
  EXPECT_EQ(usage.find("-threads"), std::string::npos);  // not this tool's
}

TEST(ToolFrames, IntrinsicsAreNeverAssumed) {
  OCC_REQUIRE_DATA(depth, "formats/open3d_rgbd/TUM_depth.png");
  OCC_REQUIRE_DATA(capture, "kinect/pcl_tutorials/pairwise/capture0001.pcd");
  OCC_REQUIRE_DATA(office, "kinect/pcl_test/office1.pcd");
  // A depth image without intrinsics anywhere is refused, naming the flags.
  EXPECT_EQ(error_of({depth}), "");  // parsing alone succeeds; reading refuses
  try {
    read_tool_frames(parse({depth}));
    FAIL() << "expected InvalidParameter";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("-intrinsics"), std::string::npos) << e.what();
  }
  const auto with_flags = read_tool_frames(parse({depth, "-intrinsics", "525,525,319.5,239.5"}));
  ASSERT_EQ(with_flags.size(), 1u);
  EXPECT_EQ(with_flags.front().camera_source, "-intrinsics");
  // An organized PCD gets its camera fitted, and says so.
  const auto fitted = read_tool_frames(parse({office}));
  ASSERT_TRUE(fitted.front().camera);
  EXPECT_NEAR(fitted.front().camera->cx, 320.0, 0.01);  // office1 is centred at 320, not 319.5
  EXPECT_NE(describe_camera(fitted).find("fitted to"), std::string::npos);
  // Frames through different cameras are refused; the paper preset needs no camera at all.
  EXPECT_THROW(read_tool_frames(parse({capture, office})), InvalidInput);
  EXPECT_FALSE(read_tool_frames(parse({"-preset", "kinect_v1_paper", capture})).front().camera);
}

// A TUM-scaled image (1/5000 m) whose values are not multiples of 5 is guessed as millimetres: its median
// lands 5 x too far, beyond the grid. Said on stderr (a scene may lie far), not with -depth_encoding given.
TEST(ToolFrames, AGuessedEncodingThatPutsTheImageBeyondTheGridIsSaid) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "occ_improve_test_beyond_grid";
  std::filesystem::create_directories(folder);
  const std::string png = (folder / "scene.png").string();
  Image16 image{64, 48, {}};
  for (int i = 0; i < 64 * 48; ++i) image.pixels.push_back(static_cast<std::uint16_t>(10001 + (i * 7) % 2000));
  write_png(png, image);
  testing::internal::CaptureStderr();
  read_tool_frames(parse({png, "-intrinsics", "52.5,52.5,31.5,23.5,64,48"}));
  const std::string guessed = testing::internal::GetCapturedStderr();
  EXPECT_NE(guessed.find("beyond the grid's 8.00 m"), std::string::npos) << guessed;
  EXPECT_NE(guessed.find("-depth_encoding"), std::string::npos) << guessed;
  testing::internal::CaptureStderr();
  read_tool_frames(parse({png, "-intrinsics", "52.5,52.5,31.5,23.5,64,48", "-depth_encoding", "tum"}));
  EXPECT_EQ(testing::internal::GetCapturedStderr().find("warning"), std::string::npos);
  std::filesystem::remove_all(folder);
}

// An unorganized cloud fits no camera: after an organized first frame it takes that frame's camera (its
// points are projected through it), and alone it is refused naming -intrinsics.
TEST(ToolFrames, AnUnorganizedCloudAfterTheFirstFrameTakesItsCamera) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "occ_improve_test_unorganized_after";
  std::filesystem::create_directories(folder);
  const std::string organized = (folder / "a_organized.pcd").string(), loose = (folder / "b_loose.pcd").string();
  pcl::io::savePCDFileBinary(organized, sample_tool_frame().cloud);
  pcl::PointCloud<pcl::PointXYZ> points;
  points.push_back({0.1f, -0.2f, 2.0f});
  points.push_back({-0.3f, 0.1f, 1.5f});
  pcl::io::savePCDFileASCII(loose, points);
  const std::vector<ToolFrame> frames = read_tool_frames(parse({organized, loose}));
  ASSERT_EQ(frames.size(), 2u);
  ASSERT_TRUE(frames[0].camera && frames[1].camera);
  EXPECT_TRUE(same_camera(*frames[0].camera, *frames[1].camera));
  EXPECT_NE(frames[1].camera_source.find("a_organized.pcd"), std::string::npos) << frames[1].camera_source;
  EXPECT_EQ(frames[1].cloud.size(), 2u);
  try {
    read_tool_frames(parse({loose}));
    FAIL() << "an unorganized cloud alone got a camera";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("-intrinsics"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(folder);
}

// Poses move every frame into the first one's sensor frame; a frame without one among posed frames is refused.
TEST(ToolFrames, PosesMoveFramesIntoTheFirstViewAndAMissingPoseIsRefused) {
  OCC_REQUIRE_DATA(frames_dir, "sequences/7scenes_redkitchen/frames");
  const std::filesystem::path folder = std::filesystem::temp_directory_path() /
                                       ("occ_improve_test_poses_" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  const std::filesystem::path source(frames_dir);
  for (const char* name : {"frame-000150.depth.png", "frame-000150.pose.txt", "frame-000170.depth.png",
                           "frame-000170.pose.txt"})
    std::filesystem::create_symlink(source / name, folder / name);
  std::filesystem::create_symlink(source.parent_path() / "camera-intrinsics.txt", folder / "camera-intrinsics.txt");
  const std::vector<ToolFrame> posed = read_tool_frames(parse({folder.string()}));
  const std::vector<ToolFrame> unposed = read_tool_frames(parse({folder.string(), "-no_poses"}));
  ASSERT_EQ(posed.size(), 2u);
  ASSERT_TRUE(posed[1].pose);
  // The first frame stays where it is; the second moves by first^-1 * second.
  EXPECT_EQ(posed[0].cloud[100000].z, unposed[0].cloud[100000].z);
  const Eigen::Isometry3d into_first = posed[0].pose->inverse() * *posed[1].pose;
  for (const std::size_t i : {std::size_t{100000}, std::size_t{200000}}) {
    const auto& p = unposed[1].cloud[i];
    if (!std::isfinite(p.z)) continue;
    const Eigen::Vector3d expected = into_first * Eigen::Vector3d(p.x, p.y, p.z);
    EXPECT_LT((expected - posed[1].cloud[i].getVector3fMap().cast<double>()).norm(), 1e-5) << i;
  }
  std::filesystem::remove(folder / "frame-000170.pose.txt");
  try {
    read_tool_frames(parse({folder.string()}));
    FAIL() << "a frame without a pose among posed frames";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("-no_poses"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_tool_frames(parse({folder.string(), "-no_poses"})).size(), 2u);
  std::filesystem::remove_all(folder);
}

// A PCD's VIEWPOINT moves its points into the sensor frame, unless -no_poses says to ignore poses (as
// -h says): then the points stay as written, so a cloud with a wrong VIEWPOINT can still be mapped.
TEST(ToolFrames, NoPosesIgnoresAPcdViewpoint) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("occ_improve_test_viewpoint_" + std::to_string(::getpid()) + ".pcd");
  std::ofstream(path) << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
                         "HEIGHT 1\nVIEWPOINT 1 0.5 -2 1 0 0 0\nPOINTS 2\nDATA ascii\n0 0 2\n0.5 0 3\n";
  const ToolFrame moved = read_tool_frames(parse({path.string(), "-intrinsics", "525,525,319.5,239.5"})).front();
  const ToolFrame as_written =
      read_tool_frames(parse({path.string(), "-intrinsics", "525,525,319.5,239.5", "-no_poses"})).front();
  std::filesystem::remove(path);
  ASSERT_TRUE(moved.pose);
  EXPECT_FLOAT_EQ(moved.cloud[1].x, -0.5f);  // 0.5 - 1: into the sensor at (1, 0.5, -2)
  EXPECT_FLOAT_EQ(moved.cloud[1].z, 5.0f);
  EXPECT_FALSE(as_written.pose);
  EXPECT_FLOAT_EQ(as_written.cloud[1].x, 0.5f);
  EXPECT_FLOAT_EQ(as_written.cloud[1].z, 3.0f);
}

// -depth_bins 100000000 took 3.1 GB before the cap error: now refused before any grid exists, while
// parsing when the camera is known (-intrinsics, or a preset without one), else when the inputs' camera is
// (preset_for_camera). The cap and the pixel sigmas are checked against that camera, not Kinect v1's
// nominal one: a 320 x 240 cloud's grid is a quarter of a 640 x 480 one's, and -sigma_angle 0.01 is 5.25 px
// at fx 525 (above the 4 px limit) but 2.6 px at fx 262.5.
TEST(ToolOptions, AGridAboveTheMemoryCapIsRefusedBeforeAnyGridForTheInputsCamera) {
  const auto cap_error = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const ResourceLimit& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(cap_error([] { parse({"-depth_bins", "100000000", "-intrinsics", "525,525,319.5,239.5"}); }).find("-depth_bins"),
            std::string::npos);
  EXPECT_NE(cap_error([] { parse({"-depth_bins", "100000000", "-preset", "kinect_v1_paper"}); }).find("-depth_bins"),
            std::string::npos);
  // Without a camera the depth axis alone is checked first (1e8 bins: ~50 GB of tables; building them
  // before the check exhausted the machine), the whole grid once the inputs give the camera.
  EXPECT_NE(cap_error([] { parse({"-depth_bins", "100000000"}); }).find("the depth axis alone"), std::string::npos);
  const ToolOptions pending = parse({"-depth_bins", "1000000"});  // ~0.5 GB alone, ~300 GB with 320 x 240 columns
  EXPECT_NE(cap_error([&] { pending.preset_for_camera(PinholeIntrinsics{262.5, 262.5, 159.5, 119.5, 320, 240}); })
                .find("-depth_bins"), std::string::npos);
  EXPECT_NO_THROW(parse({"-depth_bins", "4096"}));

  const PinholeIntrinsics qvga{262.5, 262.5, 159.5, 119.5, 320, 240};
  const ToolOptions capped = parse({"-memory_cap", "1"});  // 640 x 480 x 2048 needs 2.4 GiB, 320 x 240 0.6
  EXPECT_EQ(capped.preset_for_camera(qvga).camera->width, 320);
  EXPECT_THROW(capped.preset_for_camera(PinholeIntrinsics{525, 525, 319.5, 239.5, 640, 480}), ResourceLimit);
  const ToolOptions angle = parse({"-sigma_angle", "0.01"});
  EXPECT_NEAR(angle.preset_for_camera(qvga).model.sigma_u_px, 2.625, 1e-3);
  EXPECT_THROW(angle.preset_for_camera(std::nullopt), InvalidParameter);  // a device: the nominal camera
}

}  // namespace
}  // namespace occ_improve

namespace occ_improve {
namespace {

// run_tool on a quiet test tool whose run is `body`, the stop request cleared before and after: its exit
// code and what it wrote to stderr.
std::pair<int, std::string> run_test_tool(const std::string& description, int (*body)(const CommandLine&)) {
  const ToolFlags flags{"occ_test", {"[options]"}, description, {"-q"}, {}, {}, ""};
  char name[] = "occ_test", quiet[] = "-q";
  char* argv[] = {name, quiet, nullptr};
  clear_stop_request();
  testing::internal::CaptureStderr();
  const int code = run_tool(2, argv, flags, body);
  const std::string err = testing::internal::GetCapturedStderr();
  clear_stop_request();
  return {code, err};
}

// A signal that landed after the tool's last poll (during the final renames) was swallowed and the run
// exited 0, though the README promises 130/143: run_tool now ends in 128 + the signal whenever one came,
// saying the outputs were committed. The run here is the end of a tool: its outputs are in place when the
// signal arrives.
TEST(RunTool, ASignalAfterTheLastPollStillEndsIn128PlusTheSignal) {
  const auto [code, err] = run_test_tool("A tool that finishes while a signal arrives.\n", [](const CommandLine&) {
    std::raise(SIGTERM);  // the handler only records it: the run goes on to its end
    return 0;
  });
  EXPECT_EQ(code, 128 + SIGTERM);
  EXPECT_NE(err.find("interrupted by SIGTERM after the run had finished (its outputs are committed)"), std::string::npos)
      << err;
  // Without a signal the run's own exit code is kept.
  EXPECT_EQ(run_test_tool("A tool that finishes.\n", [](const CommandLine&) { return 0; }).first, 0);
}

// A signal during a step no poll interrupts (PCL reading a large ASCII PLY), then an error from the next
// step (a cap the file exceeds): the run was interrupted, not failed; it exited 1 with the error before.
TEST(RunTool, AnErrorAfterASignalEndsAsInterrupted) {
  const auto [code, err] = run_test_tool("A tool that fails after a signal.\n", [](const CommandLine&) -> int {
    std::raise(SIGINT);
    throw ResourceLimit("grid above the memory cap");
  });
  EXPECT_EQ(code, 128 + SIGINT);
  EXPECT_NE(err.find("grid above the memory cap"), std::string::npos) << err;
  EXPECT_NE(err.find("interrupted by SIGINT"), std::string::npos) << err;
  EXPECT_EQ(run_test_tool("A tool that fails.\n", [](const CommandLine&) -> int { throw ResourceLimit("cap"); }).first, 1);
}

}  // namespace
}  // namespace occ_improve
