// occ_plan end to end: the next shot from the sample and from a saved map with its return record, and
// bad requests giving a one-line error naming the value and a non-zero exit.
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/sample_scene.hpp"

#include "support/csv_table.hpp"
#include "support/tool_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using occ_improve::test::ToolRun;

class OccPlanTool : public ::testing::Test {
protected:
  void SetUp() override {
    // Named after the test and the process: ctest runs the tests of this file in parallel.
    dir_ = fs::temp_directory_path() / (std::string("occ_plan_test_") +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                                        std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  ToolRun run(const std::string& arguments) const {
    return occ_improve::test::run_tool_command(OCC_PLAN_EXECUTABLE, arguments, dir_ / "run.log");
  }
  static std::size_t lines(const fs::path& file) {
    std::ifstream in(file);
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);) ++n;
    return n;
  }
  // plan.txt's "name value" lines; stop's yes / no as 1 / 0, the reason left out.
  static std::map<std::string, double> plan_values(const fs::path& file) {
    std::ifstream in(file);
    std::map<std::string, double> values;
    for (std::string name, value; in >> name && std::getline(in >> std::ws, value);)
      if (name != "reason") values[name] = value == "yes" ? 1.0 : value == "no" ? 0.0 : std::stod(value);
    return values;
  }
  fs::path dir_;
};

TEST_F(OccPlanTool, SampleShotIsWritten) {
  const ToolRun r = run("-sample -budget 500 -shape rays -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "out" / "shot_mask.png"));
  EXPECT_EQ(lines(dir_ / "out" / "shot_rays.csv"), 501u);
  // The default, coarse_to_fine, asks at most one ray per block and none where the sample's flat walls
  // are predicted already: fewer than the budget after a full frame, but some (the depth edges).
  const ToolRun fine = run("-sample -budget 500 -o " + (dir_ / "fine").string());
  ASSERT_EQ(fine.exit_code, 0) << fine.output;
  EXPECT_GT(lines(dir_ / "fine" / "shot_rays.csv"), 50u);
  EXPECT_LE(lines(dir_ / "fine" / "shot_rays.csv"), 501u);
  EXPECT_NE(r.output.find("stop no"), std::string::npos) << r.output;
  // plan.txt: the rays shape stops on its own gain per ray; the default (triangles) expects rays made
  // good and stops on the mean score of the view's best fifth (planner.hpp), below -stop_gain 0.1.
  const auto rays = plan_values(dir_ / "out" / "plan.txt"), triangles = plan_values(dir_ / "fine" / "plan.txt");
  EXPECT_GT(rays.at("expected_gain"), 0.0);
  EXPECT_NEAR(rays.at("stop_gain_per_ray"), rays.at("expected_gain") / 500, 1e-6 * rays.at("stop_gain_per_ray"));
  EXPECT_EQ(rays.at("ranked_rays"), 500.0);
  EXPECT_GT(triangles.at("stop_gain_per_ray"), 0.0);
  EXPECT_EQ(triangles.at("stop") == 1.0, triangles.at("stop_gain_per_ray") < 0.1);
  // -stop_share 1: the whole view's mean, lower than its best fifth's; out of (0, 1]: one line, exit 1.
  ASSERT_EQ(run("-sample -budget 500 -stop_share 1 -o " + (dir_ / "all").string()).exit_code, 0);
  EXPECT_LT(plan_values(dir_ / "all" / "plan.txt").at("stop_gain_per_ray"), triangles.at("stop_gain_per_ray"));
  const ToolRun bad = run("-sample -stop_share 0 -o " + (dir_ / "bad").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("-stop_share"), std::string::npos) << bad.output;
}

// -o never overwrites what the tool did not write: a folder with a user's file is refused (naming
// -overwrite) and the file is intact; the tool's own previous output is replaced.
TEST_F(OccPlanTool, AForeignOutputFolderIsRefusedAndItsOwnIsReplaced) {
  const fs::path user = dir_ / "user";
  fs::create_directories(user);
  std::ofstream(user / "shot_mask.png") << "mine";
  const ToolRun refused = run("-sample -budget 100 -o " + user.string());
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find("-overwrite"), std::string::npos) << refused.output;
  std::ifstream in(user / "shot_mask.png");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "mine");
  ASSERT_EQ(run("-sample -budget 100 -shape rays -o " + (dir_ / "out").string()).exit_code, 0);
  const ToolRun again = run("-sample -budget 200 -shape rays -o " + (dir_ / "out").string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(lines(dir_ / "out" / "shot_rays.csv"), 201u);
}

TEST_F(OccPlanTool, SavedMapBringsItsReturnRecord) {
  occ_improve::Mapper mapper(occ_improve::kinect_v1());
  const auto points = occ_improve::sample::generate_scene().points();
  mapper.insert(occ_improve::PointSpan::from(points));
  auto returns = occ_improve::ReturnRecord::for_grid(640, 480);
  returns.record_shot({10, 11, 12}, {1, 0, 0});
  occ_improve::save_map((dir_ / "map.occmap").string(), mapper.grid(), mapper.model().params(), returns);
  const ToolRun r = run("-load " + (dir_ / "map.occmap").string() + " -shape window -window 8x4 -budget 32 -o " +
                        (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 rays asked, 1 returned"), std::string::npos) << r.output;
  EXPECT_EQ(lines(dir_ / "out" / "shot_rays.csv"), 33u);
}

// shot_rays.csv's score is what the plan ranked by (shot_scores: improvement x return probability, with
// the discount for rays whose returns did not settle them), not improvement x return probability alone.
TEST_F(OccPlanTool, ScoreColumnIsThePlansScore) {
  occ_improve::Mapper mapper(occ_improve::kinect_v1());
  const auto points = occ_improve::sample::generate_scene().points();
  mapper.insert(occ_improve::PointSpan::from(points));
  auto returns = occ_improve::ReturnRecord::for_grid(640, 480);
  std::vector<occ_improve::ColumnIndex> unsettled;  // rays with no data in the map, recorded as returned 3 times
  for (occ_improve::ColumnIndex c = 0; c < 640 * 480 && unsettled.size() < 100; c += 97)
    if (mapper.improvement().value[c] >= 0.3f) unsettled.push_back(c);
  ASSERT_EQ(unsettled.size(), 100u);
  for (int shot = 0; shot < 3; ++shot) returns.record_shot(unsettled, std::vector<std::uint8_t>(unsettled.size(), 1));
  occ_improve::save_map((dir_ / "map.occmap").string(), mapper.grid(), mapper.model().params(), returns);
  const ToolRun r = run("-load " + (dir_ / "map.occmap").string() + " -budget 307200 -o " + (dir_ / "out").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const occ_improve::test::CsvTable rays = occ_improve::test::read_csv(dir_ / "out" / "shot_rays.csv");
  ASSERT_EQ(rays.rows.size(), 307200u);
  const std::vector<float> expected = occ_improve::shot_scores(mapper.improvement(), returns, occ_improve::ReturnModelParams{});
  const std::vector<double> column = rays.column("column"), score = rays.column("score"),
                            improvement = rays.column("improvement"), p = rays.column("return_probability");
  std::size_t discounted = 0;
  for (std::size_t i = 0; i < column.size(); ++i) {
    const double e = expected[static_cast<std::size_t>(column[i])];
    ASSERT_NEAR(score[i], e, 1e-5 * std::max(1.0, std::abs(e))) << "column " << column[i];
    discounted += improvement[i] > 0 && score[i] < 0.5 * improvement[i] * p[i] ? 1 : 0;  // 2 / (2 + 3) of it
  }
  EXPECT_EQ(discounted, unsettled.size());
}

// -predicted_depth RULE writes the map's dense predicted depth as 16-bit millimetres: read back, every
// pixel is the library's prediction from the same map (rounded to the millimetre, 0 = none); linear and
// nearest differ between the 5 % samples.
TEST_F(OccPlanTool, PredictedDepthIsWrittenInMillimetres) {
  occ_improve::Mapper mapper(occ_improve::kinect_v1());
  std::vector<Eigen::Vector3f> points;
  std::mt19937 rng(4);
  std::bernoulli_distribution keep(0.05);
  for (const auto& p : occ_improve::sample::generate_scene().points())
    if (std::isfinite(p.z()) && keep(rng)) points.push_back(p);
  mapper.insert(occ_improve::PointSpan::from(points));
  occ_improve::save_map((dir_ / "map.occmap").string(), mapper.grid(), mapper.model().params());
  std::vector<double> mean_mm;
  for (const std::string rule : {"nearest", "linear"}) {
    const fs::path out = dir_ / rule;
    const ToolRun r = run("-load " + (dir_ / "map.occmap").string() + " -budget 100 -predicted_depth " + rule +
                          " -radius 8 -o " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("predicted_depth.png"), std::string::npos) << r.output;
    occ_improve::DepthPredictionParams params;
    params.rule = rule == "linear" ? occ_improve::DepthPredictionRule::linear : occ_improve::DepthPredictionRule::nearest;
    params.radius_columns = 8;
    const occ_improve::PredictedDepth expected = occ_improve::predict_depth(mapper.surface(), mapper.model(), params);
    const occ_improve::LoadedFrame read = occ_improve::load_depth_frame(
        (out / "predicted_depth.png").string(), occ_improve::kinect_v1_intrinsics(), occ_improve::DepthEncoding::millimetres);
    ASSERT_EQ(read.cloud.width, 640u);
    ASSERT_EQ(read.cloud.height, 480u);
    std::size_t predicted = 0, mismatched = 0;
    double sum_mm = 0;
    for (std::size_t c = 0; c < expected.depth_m.size(); ++c) {
      const float z = read.cloud[c].z;
      const bool has = std::isfinite(z) && z > 0;
      const double want_mm = expected.distance[c] >= 0 ? std::round(1000.0 * expected.depth_m[c]) : 0.0;
      if (has != (want_mm > 0) || (has && std::abs(1000.0 * z - want_mm) > 0.01)) ++mismatched;
      if (has) {
        ++predicted;
        sum_mm += 1000.0 * z;
      }
    }
    EXPECT_EQ(mismatched, 0u) << rule;
    EXPECT_GT(predicted, expected.depth_m.size() / 2) << rule;
    mean_mm.push_back(sum_mm / static_cast<double>(predicted));
  }
  EXPECT_NE(mean_mm[0], mean_mm[1]);
  EXPECT_EQ(run("-load " + (dir_ / "map.occmap").string() + " -predicted_depth cubic -o " + (dir_ / "bad").string()).exit_code, 1);
}

TEST_F(OccPlanTool, BadRequestsNameTheValue) {
  const std::string out = " -o " + (dir_ / "out").string();
  ToolRun r = run("-sample -budget 0" + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("-budget 0 is invalid"), std::string::npos) << r.output;
  r = run("-sample -budget 400000" + out);
  EXPECT_EQ(r.exit_code, 1);
  // Named by the flags, not the library's struct fields (issue 24).
  EXPECT_NE(r.output.find("error: -budget 400000 is more than the grid's 640 x 480 = 307200 rays"), std::string::npos)
      << r.output;
  r = run("-sample -shape spiral" + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("-shape spiral"), std::string::npos) << r.output;
  r = run("-sample -shape window -window 64x64 -budget 100" + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("error: -window 64x64 covers 4096 rays, more than -budget 100: raise -budget or shrink -window"),
            std::string::npos)
      << r.output;
  r = run("-sample -shape window -window 700x10 -budget 7000" + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("error: -window 700x10 does not fit in the grid of 640 x 480 columns"), std::string::npos)
      << r.output;
  for (const char* field : {"budget_rays", "window_width_columns", "window_height_columns"})
    EXPECT_EQ(r.output.find(field), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace
