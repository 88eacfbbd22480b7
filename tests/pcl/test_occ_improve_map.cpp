// occ_improve_map end to end, as a user runs it: outputs on the built-in sample, and bad input giving a
// one-line error, a non-zero exit and no output folder.
#include "support/tool_run.hpp"

#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
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
// the tests of this file in parallel.
ToolRun run_tool(const std::string& arguments) {
  return occ_improve::test::run_tool_command(
      OCC_IMPROVE_MAP_EXECUTABLE, arguments,
      fs::temp_directory_path() / ("occ_improve_map_test_" + std::to_string(::getpid()) + ".log"));
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
