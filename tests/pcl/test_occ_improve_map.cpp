// occ_improve_map end to end, as a user runs it: outputs on the built-in sample, and bad input giving a
// one-line error, a non-zero exit and no output folder.
#include "occ_improve/sample_scene.hpp"
#include "support/csv_table.hpp"
#include "support/test_data.hpp"
#include "support/tool_run.hpp"

#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using occ_improve::test::ToolRun;

// The log lives outside the test's folder (whose entries the tests count), one per process: ctest runs
// the tests of this file in parallel. Removed once read (81 of them had piled up in /tmp).
ToolRun run_tool(const std::string& arguments) {
  const fs::path log = fs::temp_directory_path() / ("occ_improve_map_test_" + std::to_string(::getpid()) + ".log");
  ToolRun run = occ_improve::test::run_tool_command(OCC_IMPROVE_MAP_EXECUTABLE, arguments, log);
  fs::remove(log);
  return run;
}

class OccImproveMapTool : public ::testing::Test {
protected:
  void SetUp() override {
    // Named after the test and the process: ctest runs the tests of this file in parallel.
    dir_ = fs::temp_directory_path() / (std::string("occ_improve_map_test_") +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                                        std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(OccImproveMapTool, SampleRunWritesEveryOutput) {
  const fs::path out = dir_ / "out";
  const ToolRun r = run_tool("-sample -k 5 -o " + out.string() + " -save " + (dir_ / "map.occmap").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"depth.png", "occupancy.png", "improvement.png", "legend.png", "surface.pcd", "regions.csv"})
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "map.occmap"));
  EXPECT_NE(r.output.find("stop:"), std::string::npos) << r.output;
  // The surface cloud opens with its fields, organized like the grid.
  pcl::PCLPointCloud2 cloud;
  ASSERT_EQ(pcl::io::loadPCDFile((out / "surface.pcd").string(), cloud), 0);
  EXPECT_EQ(cloud.width, 640u);
  EXPECT_EQ(cloud.height, 480u);
  std::string fields;
  for (const auto& f : cloud.fields) fields += f.name + " ";
  EXPECT_EQ(fields, "x y z surface_depth probability improvement ");
  // regions.csv: at most K rows, sorted by summed improvement.
  std::ifstream csv(out / "regions.csv");
  std::string line;
  std::getline(csv, line);
  double previous = 1e300;
  int rows = 0;
  while (std::getline(csv, line)) {
    const double summed = std::stod(line.substr(line.find(',') + 1));
    EXPECT_LE(summed, previous);
    previous = summed;
    ++rows;
  }
  EXPECT_GE(rows, 1);
  EXPECT_LE(rows, 5);
  // Resuming from the saved map reproduces the ranking.
  const fs::path resumed = dir_ / "resumed";
  ASSERT_EQ(run_tool("-load " + (dir_ / "map.occmap").string() + " -k 5 -o " + resumed.string()).exit_code, 0);
  std::ifstream a(out / "regions.csv"), b(resumed / "regions.csv");
  std::stringstream ta, tb;
  ta << a.rdbuf();
  tb << b.rdbuf();
  EXPECT_EQ(ta.str(), tb.str());
}

TEST_F(OccImproveMapTool, BadInputFailsCleanlyWithoutOutput) {
  const fs::path out = dir_ / "out";
  const fs::path garbage = dir_ / "garbage.pcd";
  std::ofstream(garbage) << "not a point cloud\n";
  const fs::path empty = dir_ / "empty.pcd";
  std::ofstream{empty};
  for (const std::string& args : {std::string("-sample -k 0"), garbage.string(), empty.string(),
                                  (dir_ / "missing.pcd").string(), std::string("-sample -preset nonsense")}) {
    const ToolRun r = run_tool(args + " -o " + out.string());
    EXPECT_EQ(r.exit_code, 1) << args << ": " << r.output;
    EXPECT_NE(r.output.find("error: "), std::string::npos) << args << ": " << r.output;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
  // An output folder that cannot be created.
  const ToolRun r = run_tool("-sample -o /proc/occ_improve_out");
  EXPECT_EQ(r.exit_code, 1) << r.output;
}

constexpr double kDeg = 180.0 / 3.14159265358979323846;

// rays.csv gave pixel indices times 180/pi as degrees with the pixel-native default (azimuth_deg 57.3
// for pixel 1), and its ties went in scan order (the first ten rays: one row, ten neighbouring columns).
TEST_F(OccImproveMapTool, RaysCsvGivesPixelsDirectionsAndTrueAnglesWithTiesSpread) {
  const fs::path out = dir_ / "out";
  const ToolRun r = run_tool("-sample -k 50 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const occ_improve::test::CsvTable rays = occ_improve::test::read_csv(out / "rays.csv");
  ASSERT_EQ(rays.rows.size(), 50u);
  const std::vector<std::string> header = {"rank",        "improvement", "column_u",      "row_v",         "direction_x",
                                           "direction_y", "direction_z", "azimuth_deg", "elevation_deg", "depth_m"};
  EXPECT_EQ(rays.header, header);
  const auto camera = occ_improve::sample::generate_scene().intrinsics;  // the default preset's columns are its pixels
  std::set<int> rows;
  for (std::size_t i = 0; i < rays.rows.size(); ++i) {
    const double u = rays.value(i, "column_u"), v = rays.value(i, "row_v");
    const double x = rays.value(i, "direction_x"), y = rays.value(i, "direction_y"), z = rays.value(i, "direction_z");
    ASSERT_TRUE(u >= 0 && u < camera.width && v >= 0 && v < camera.height) << u << ", " << v;
    // The unit ray through pixel (u, v).
    const double px = (u - camera.cx) / camera.fx, py = (v - camera.cy) / camera.fy, n = std::sqrt(px * px + py * py + 1);
    EXPECT_NEAR(x, px / n, 2e-6) << i;
    EXPECT_NEAR(y, py / n, 2e-6) << i;
    EXPECT_NEAR(z, 1 / n, 2e-6) << i;
    // Degrees of that ray (CONVENTIONS 1), inside the camera's field of view (+-28.7 x +-22.3 deg).
    EXPECT_NEAR(rays.value(i, "azimuth_deg"), std::atan2(x, z) * kDeg, 2e-3) << i;
    EXPECT_NEAR(rays.value(i, "elevation_deg"), std::atan2(y, std::hypot(x, z)) * kDeg, 2e-3) << i;
    EXPECT_LT(std::abs(rays.value(i, "azimuth_deg")), 29.0) << i;
    EXPECT_LT(std::abs(rays.value(i, "elevation_deg")), 23.0) << i;
    if (i > 0) {
      EXPECT_LE(rays.value(i, "improvement"), rays.value(i - 1, "improvement")) << i;
    }
    if (i < 10) rows.insert(static_cast<int>(v));
  }
  // The sample's best rays are its many no-data rays, all of one value: the tie is spread over the view.
  EXPECT_EQ(rays.value(0, "improvement"), rays.value(9, "improvement"));
  EXPECT_GE(rows.size(), 8u) << "the first ten rays fall on " << rows.size() << " rows";

  // The spherical preset: the angles are the bins' centres (57 x 43 deg in 640 x 480 bins).
  const fs::path paper = dir_ / "paper";
  ASSERT_EQ(run_tool("-sample -preset kinect_v1_paper -k 20 -o " + paper.string()).exit_code, 0);
  const occ_improve::test::CsvTable spherical = occ_improve::test::read_csv(paper / "rays.csv");
  ASSERT_EQ(spherical.rows.size(), 20u);
  for (std::size_t i = 0; i < spherical.rows.size(); ++i) {
    EXPECT_NEAR(spherical.value(i, "azimuth_deg"), -28.5 + (spherical.value(i, "column_u") + 0.5) * 57.0 / 640, 2e-3);
    EXPECT_NEAR(spherical.value(i, "elevation_deg"), -21.5 + (spherical.value(i, "row_v") + 0.5) * 43.0 / 480, 2e-3);
  }
}

// One float field of an organized cloud at pixel (u, v).
float field_at(const pcl::PCLPointCloud2& cloud, const std::string& name, int u, int v) {
  for (const auto& f : cloud.fields)
    if (f.name == name) {
      float value;
      std::memcpy(&value, &cloud.data[static_cast<std::size_t>(v) * cloud.row_step + static_cast<std::size_t>(u) * cloud.point_step + f.offset],
                  sizeof value);
      return value;
    }
  ADD_FAILURE() << "no field " << name;
  return NAN;
}

// regions.csv gave a region's mean position, which on a real table scene lay on the table, outside the
// region (the region is the band of no data around the objects). Its centre is now one of its pixels.
TEST_F(OccImproveMapTool, RegionCentresArePixelsOfTheirRegionsOnARealTableScene) {
  // learn8: its best region (the no-data area around the table: floor and walls cropped) has its mean
  // position on the table, at pixel (379, 130), 1.13 m away; 9 of the 10 mosd_learn clouds are alike.
  OCC_REQUIRE_DATA(cloud_path, "segmentation/mosd_learn/learn8.pcd");
  const fs::path out = dir_ / "out";
  const ToolRun r = run_tool(cloud_path + " -k 10 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  pcl::PCLPointCloud2 surface;
  ASSERT_EQ(pcl::io::loadPCDFile((out / "surface.pcd").string(), surface), 0);
  const occ_improve::test::CsvTable regions = occ_improve::test::read_csv(out / "regions.csv");
  ASSERT_GE(regions.rows.size(), 3u);
  for (std::size_t i = 0; i < regions.rows.size(); ++i) {
    const auto at = [&](const char* name) { return static_cast<int>(regions.value(i, name)); };
    const int cu = at("centre_u"), cv = at("centre_v"), pu = at("peak_u"), pv = at("peak_v");
    EXPECT_GE(field_at(surface, "improvement", cu, cv), 0.2f) << "region " << i + 1 << ": centre (" << cu << ", " << cv
                                                              << ") is not in the region";
    EXPECT_NEAR(field_at(surface, "improvement", pu, pv), regions.value(i, "peak_improvement"), 1e-5) << i;
    EXPECT_TRUE(at("min_u") <= cu && cu <= at("max_u") && at("min_v") <= cv && cv <= at("max_v")) << i;
    EXPECT_TRUE(at("min_u") <= pu && pu <= at("max_u") && at("min_v") <= pv && pv <= at("max_v")) << i;
    const double x = regions.value(i, "direction_x"), y = regions.value(i, "direction_y"), z = regions.value(i, "direction_z");
    EXPECT_NEAR(std::sqrt(x * x + y * y + z * z), 1.0, 1e-5);
    // The direction is the centre pixel's: below the image's centre row (v grows downwards), y > 0.
    EXPECT_EQ(y > 0, cv >= 240) << i;  // cy = 239.5
    EXPECT_NEAR(regions.value(i, "elevation_deg"), std::atan2(y, std::hypot(x, z)) * kDeg, 2e-3) << i;
  }
}

std::string contents(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A small organized frame: a wall 2 m in front of the sensor.
void write_wall_pcd(const fs::path& path) {
  pcl::PointCloud<pcl::PointXYZ> cloud(64, 48);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) cloud.at(u, v) = pcl::PointXYZ((u - 32) * 0.01f, (v - 24) * 0.01f, 2.0f);
  ASSERT_EQ(pcl::io::savePCDFileBinary(path.string(), cloud), 0);
}

// The data loss: `-o` naming a dataset folder erased its frames, poses and intrinsics.
TEST_F(OccImproveMapTool, DatasetFolderAsOutputIsRefusedAndKept) {
  const fs::path ds = dir_ / "ds";
  fs::create_directories(ds / "seq-01");
  std::ofstream(ds / "camera-intrinsics.txt") << "585 0 320\n0 585 240\n0 0 1\n";
  std::ofstream(ds / "seq-01" / "frame-000000.pose.txt") << "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  const ToolRun r = run_tool("-sample -o " + ds.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("-overwrite"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << "one line: " << r.output;
  EXPECT_EQ(contents(ds / "camera-intrinsics.txt"), "585 0 320\n0 585 240\n0 0 1\n");
  EXPECT_TRUE(fs::is_regular_file(ds / "seq-01" / "frame-000000.pose.txt"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1) << "no staging folder left";
  // With -overwrite the outputs join the dataset's files; nothing of the dataset is removed.
  const ToolRun forced = run_tool("-sample -overwrite -o " + ds.string());
  ASSERT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_TRUE(fs::is_regular_file(ds / "improvement.png"));
  EXPECT_EQ(contents(ds / "camera-intrinsics.txt"), "585 0 320\n0 585 240\n0 0 1\n");
  EXPECT_TRUE(fs::is_regular_file(ds / "seq-01" / "frame-000000.pose.txt"));
}

// `dot/office1.pcd -o dot` erased its own input.
TEST_F(OccImproveMapTool, InputsFolderAsOutputIsRefusedAndTheInputKept) {
  const fs::path dot = dir_ / "dot", input = dot / "office1.pcd";
  fs::create_directories(dot);
  write_wall_pcd(input);
  const std::string before = contents(input);
  const ToolRun r = run_tool(input.string() + " -o " + dot.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("-overwrite"), std::string::npos) << r.output;
  EXPECT_EQ(contents(input), before);
  EXPECT_EQ(std::distance(fs::directory_iterator(dot), fs::directory_iterator()), 1);
}

TEST_F(OccImproveMapTool, RerunIntoItsOwnOutputReplacesIt) {
  const fs::path out = dir_ / "out", input = dir_ / "wall.pcd";
  write_wall_pcd(input);
  ASSERT_EQ(run_tool(input.string() + " -o " + out.string()).exit_code, 0);
  const ToolRun again = run_tool(input.string() + " -o " + out.string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_TRUE(fs::is_regular_file(out / ".occ_improve_output"));
  EXPECT_EQ(contents(out / ".occ_improve_output").rfind("occ_improve_map\n", 0), 0u);
  // A file of the user's own in it makes it a folder the tool did not write.
  std::ofstream(out / "notes.txt") << "mine";
  EXPECT_EQ(run_tool(input.string() + " -o " + out.string()).exit_code, 1);
  EXPECT_EQ(contents(out / "notes.txt"), "mine");
}

}  // namespace
