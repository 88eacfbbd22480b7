// occ_improve_map end to end, as a user runs it: outputs on the built-in sample, and bad input giving a
// one-line error, a non-zero exit and no output folder.
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

struct ToolRun {
  int exit_code;
  std::string output;
};

ToolRun run_tool(const std::string& arguments) {
  const fs::path log = fs::temp_directory_path() / "occ_improve_map_test.log";
  const std::string command = std::string(OCC_IMPROVE_MAP_EXECUTABLE) + " " + arguments + " > " + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

class OccImproveMapTool : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("occ_improve_map_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
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

}  // namespace
