// Issue 24's tool items, end to end as a user runs the tools: the validity / region-of-interest mask
// (-mask) on a real mOSD cloud, and the 16-bit images beside the CSVs and colour pictures (regions.png,
// depth_mm.png), whose values are read back and compared with the CSVs and the surface cloud.
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/point_types.hpp"
#include "occ_improve/sample_scene.hpp"
#include "support/csv_table.hpp"
#include "support/test_data.hpp"
#include "support/tool_run.hpp"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using occ_improve::test::CsvTable;
using occ_improve::test::ToolRun;

class ToolMasksAndImages : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / (std::string("occ_tool_masks_test_") +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                                        std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  ToolRun run(const std::string& executable, const std::string& arguments) const {
    return occ_improve::test::run_tool_command(executable, arguments, dir_ / "run.log");
  }
  fs::path dir_;
};

// The cloud's finite points as a mask PNG (255 = valid), what a user would draw for a cropped cloud.
occ_improve::PixelMask write_finite_mask(const std::string& cloud_path, const fs::path& png) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  EXPECT_EQ(pcl::io::loadPCDFile(cloud_path, cloud), 0);
  occ_improve::Image image{static_cast<int>(cloud.width), static_cast<int>(cloud.height), 1,
                           std::vector<std::uint8_t>(cloud.size(), 0)};
  occ_improve::PixelMask mask{image.width, image.height, std::vector<std::uint8_t>(cloud.size(), 0)};
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (std::isfinite(cloud[i].z)) image.pixels[i] = 255, mask.valid[i] = 1;
  occ_improve::write_png(png.string(), image);
  return mask;
}

std::size_t pixel(const CsvTable& t, std::size_t row, const char* u, const char* v, int width = 640) {
  return static_cast<std::size_t>(t.value(row, v)) * width + static_cast<std::size_t>(t.value(row, u));
}

// The case: mOSD learn0 has its floor and walls cropped to NaN, and today region 1 is that cropped
// background (over 100,000 rays of the no-data level). With a mask of the cloud's finite points no region,
// ray or planned shot lies outside it, and the improvement there is NaN (grey).
TEST_F(ToolMasksAndImages, MaskKeepsTheCroppedBackgroundOfAnMosdCloudOutOfEveryResult) {
  OCC_REQUIRE_DATA(cloud, "segmentation/mosd_learn/learn0.pcd");
  const occ_improve::PixelMask mask = write_finite_mask(cloud, dir_ / "mask.png");
  ASSERT_GT(mask.valid_count(), 100000u);
  const fs::path plain = dir_ / "plain", masked = dir_ / "masked", finite = dir_ / "finite";
  ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, cloud + " -k 10 -o " + plain.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable before = occ_improve::test::read_csv(plain / "regions.csv");
  ASSERT_FALSE(before.rows.empty());
  EXPECT_GT(before.value(0, "area_columns"), 100000);  // today: the cropped background
  EXPECT_FALSE(mask.valid[pixel(before, 0, "peak_u", "peak_v")]);

  r = run(OCC_IMPROVE_MAP_EXECUTABLE, cloud + " -k 10 -mask " + (dir_ / "mask.png").string() + " -o " + masked.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pixels valid"), std::string::npos) << r.output;
  const CsvTable regions = occ_improve::test::read_csv(masked / "regions.csv");
  ASSERT_FALSE(regions.rows.empty());
  EXPECT_LT(regions.value(0, "area_columns"), 1000);
  // Every ray of every region inside the mask (regions.png names them), and every ranked ray.
  const occ_improve::DepthImage16 ids = occ_improve::read_depth_image16((masked / "regions.png").string());
  ASSERT_EQ(ids.values.size(), mask.valid.size());
  std::size_t labelled = 0;
  for (std::size_t i = 0; i < ids.values.size(); ++i)
    if (ids.values[i] != 0) {
      EXPECT_TRUE(mask.valid[i]) << "pixel " << i << " of region " << ids.values[i] << " is outside the mask";
      ++labelled;
    }
  EXPECT_GT(labelled, 0u);
  const CsvTable rays = occ_improve::test::read_csv(masked / "rays.csv");
  ASSERT_EQ(rays.rows.size(), 10u);
  for (std::size_t i = 0; i < rays.rows.size(); ++i) EXPECT_TRUE(mask.valid[pixel(rays, i, "column_u", "row_v")]) << i;
  // NaN improvement exactly outside the mask (grey in improvement.png).
  pcl::PointCloud<occ_improve::PointImprovement> surface;
  ASSERT_EQ(pcl::io::loadPCDFile((masked / "surface.pcd").string(), surface), 0);
  ASSERT_EQ(surface.size(), mask.valid.size());
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < surface.size(); ++i) wrong += std::isnan(surface[i].improvement) == (mask.valid[i] != 0);
  EXPECT_EQ(wrong, 0u);

  // -mask finite is the same mask, built from the frame.
  r = run(OCC_IMPROVE_MAP_EXECUTABLE, cloud + " -k 10 -mask finite -o " + finite.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(occ_improve::test::read_csv(finite / "regions.csv").rows, regions.rows);

  // occ_plan never takes a ray outside the mask; without it, most of the shot goes to the cropped
  // background (the default triangles plan: its coverage pass there and the triangles spanning it; the
  // rest refines the data's edges), and nearly all of it with -refine residual.
  const auto outside_share = [&](const fs::path& out) {
    const CsvTable shot = occ_improve::test::read_csv(out / "shot_rays.csv");
    std::size_t outside = 0;
    for (std::size_t i = 0; i < shot.rows.size(); ++i)
      outside += !mask.valid[static_cast<std::size_t>(shot.value(i, "column"))];
    return shot.rows.empty() ? -1.0 : static_cast<double>(outside) / static_cast<double>(shot.rows.size());
  };
  r = run(OCC_PLAN_EXECUTABLE, cloud + " -budget 2000 -o " + (dir_ / "plan_plain").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(outside_share(dir_ / "plan_plain"), 0.5);
  r = run(OCC_PLAN_EXECUTABLE, cloud + " -budget 2000 -refine residual -o " + (dir_ / "plan_residual").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(outside_share(dir_ / "plan_residual"), 0.9);
  r = run(OCC_PLAN_EXECUTABLE, cloud + " -budget 2000 -mask " + (dir_ / "mask.png").string() + " -o " +
                                   (dir_ / "plan_masked").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(outside_share(dir_ / "plan_masked"), 0.0);

  // occ_segment: no point outside the mask carries a label.
  r = run(OCC_SEGMENT_EXECUTABLE, cloud + " -mask " + (dir_ / "mask.png").string() + " -o " + (dir_ / "seg").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  pcl::PointCloud<pcl::PointXYZRGBL> labels;
  ASSERT_EQ(pcl::io::loadPCDFile((dir_ / "seg" / "labels.pcd").string(), labels), 0);
  std::size_t labelled_outside = 0, labelled_inside = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) (mask.valid[i] ? labelled_inside : labelled_outside) += labels[i].label != 0;
  EXPECT_EQ(labelled_outside, 0u);
  EXPECT_GT(labelled_inside, 10000u);
  // label_ids.png: the 16-bit label of each ray beside the colour labels.png; its label counts are
  // segments.csv's rays.
  const occ_improve::DepthImage16 label_ids =
      occ_improve::read_depth_image16((dir_ / "seg" / "label_ids.png").string());
  ASSERT_EQ(label_ids.values.size(), mask.valid.size());
  std::map<int, std::size_t> rays_of;
  for (std::size_t i = 0; i < label_ids.values.size(); ++i)
    if (label_ids.values[i] != 0) {
      ++rays_of[label_ids.values[i]];
      EXPECT_TRUE(mask.valid[i]) << "ray " << i << " of label " << label_ids.values[i] << " is outside the mask";
    }
  const CsvTable segments = occ_improve::test::read_csv(dir_ / "seg" / "segments.csv");
  ASSERT_GE(segments.rows.size(), 2u);
  EXPECT_EQ(rays_of.size(), segments.rows.size());
  for (std::size_t i = 0; i < segments.rows.size(); ++i)
    EXPECT_EQ(rays_of[static_cast<int>(segments.value(i, "label"))],
              static_cast<std::size_t>(segments.value(i, "rays")))
        << "label " << segments.value(i, "label");
}

TEST_F(ToolMasksAndImages, AMaskOfAnotherSizeOrFormatIsRefusedInOneLineNamingTheFlag) {
  occ_improve::Image small{320, 240, 1, std::vector<std::uint8_t>(320 * 240, 255)};
  occ_improve::write_png((dir_ / "small.png").string(), small);
  occ_improve::Image rgb{640, 480, 3, std::vector<std::uint8_t>(640 * 480 * 3, 255)};
  occ_improve::write_png((dir_ / "rgb.png").string(), rgb);
  for (const char* tool : {OCC_IMPROVE_MAP_EXECUTABLE, OCC_PLAN_EXECUTABLE, OCC_TO_OCTOMAP_EXECUTABLE}) {
    const std::string out = (dir_ / (std::string("out_") + fs::path(tool).filename().string())).string() +
                            (std::string(tool) == OCC_TO_OCTOMAP_EXECUTABLE ? ".bt" : "");
    ToolRun r = run(tool, "-sample -mask " + (dir_ / "small.png").string() + " -o " + out);
    EXPECT_EQ(r.exit_code, 1) << tool << ": " << r.output;
    EXPECT_NE(r.output.find("error: -mask " + (dir_ / "small.png").string() + ": mask is 320 x 240, the camera 640 x 480"),
              std::string::npos)
        << tool << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(out)) << tool;
    r = run(tool, "-sample -mask " + (dir_ / "rgb.png").string() + " -o " + out);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("must be 8-bit or 16-bit single-channel"), std::string::npos) << r.output;
  }
}

// A mask that leaves no ray is refused naming the mask and the input, not the field of view; a mask
// that leaves half counts the points it left out in the summary's point line.
TEST_F(ToolMasksAndImages, AMaskLeavingNoPointIsNamedAndMaskedPointsAreCounted) {
  occ_improve::Image none{640, 480, 1, std::vector<std::uint8_t>(640 * 480, 0)};
  occ_improve::write_png((dir_ / "none.png").string(), none);
  ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-sample -mask " + (dir_ / "none.png").string() + " -o " +
                                                  (dir_ / "out_none").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("error: -mask " + (dir_ / "none.png").string() + " leaves out every pixel"),
            std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "out_none"));
  // occ_segment wrote an empty segmentation, exiting 0 (so did occ_improve_live -simulate: the same check).
  const std::string sample_pcd = (dir_ / "sample.pcd").string();
  const occ_improve::sample::SampleFrame scene = occ_improve::sample::generate_scene();
  pcl::io::savePCDFileBinary(sample_pcd, occ_improve::organized_cloud(scene.points(), scene.intrinsics.width,
                                                                      scene.intrinsics.height));
  r = run(OCC_SEGMENT_EXECUTABLE, sample_pcd + " -mask " + (dir_ / "none.png").string() + " -o " + (dir_ / "seg_none").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("leaves out every pixel"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "seg_none"));

  occ_improve::Image left{640, 480, 1, std::vector<std::uint8_t>(640 * 480, 0)};
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 320; ++u) left.pixels[static_cast<std::size_t>(v) * 640 + u] = 255;
  occ_improve::write_png((dir_ / "left.png").string(), left);
  r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-sample -mask " + (dir_ / "left.png").string() + " -o " +
                                          (dir_ / "out_left").string() + " -save " + (dir_ / "left.occmap").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The map holds the grid, not the mask: said, since a plan from the loaded map would aim at left-out rays.
  EXPECT_NE(r.output.find("warning: -save keeps the grid, not the -mask"), std::string::npos) << r.output;
  unsigned long read = 0, used = 0, invalid = 0, outside = 0, masked = 0;
  const std::size_t at = r.output.find("points: ");
  ASSERT_NE(at, std::string::npos) << r.output;
  ASSERT_EQ(std::sscanf(r.output.c_str() + at, "points: %lu read, %lu used, %lu skipped invalid, %lu skipped outside",
                        &read, &used, &invalid, &outside), 4) << r.output;
  const std::size_t masked_at = r.output.find(" skipped outside -mask");
  ASSERT_NE(masked_at, std::string::npos) << r.output;
  const std::size_t number_at = r.output.rfind("; ", masked_at);
  ASSERT_EQ(std::sscanf(r.output.c_str() + number_at, "; %lu", &masked), 1) << r.output;
  EXPECT_EQ(read, 640ul * 480ul);  // every point read, before the mask
  EXPECT_GT(masked, 100000ul);
  EXPECT_EQ(read, used + invalid + outside + masked);
}

// regions.png holds regions.csv's ranks: each id's pixels are its row's area, inside its bounding box,
// with its peak; 0 elsewhere.
TEST_F(ToolMasksAndImages, RegionsPngHoldsTheIdsOfRegionsCsv) {
  const fs::path out = dir_ / "out";
  const ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-sample -k 6 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable regions = occ_improve::test::read_csv(out / "regions.csv");
  ASSERT_GE(regions.rows.size(), 3u);
  const occ_improve::DepthImage16 ids = occ_improve::read_depth_image16((out / "regions.png").string());
  ASSERT_EQ(ids.width, 640);
  ASSERT_EQ(ids.height, 480);
  std::map<int, std::size_t> area;
  std::map<int, std::array<int, 4>> box;  // min u, min v, max u, max v
  for (int v = 0; v < ids.height; ++v)
    for (int u = 0; u < ids.width; ++u) {
      const int id = ids.values[static_cast<std::size_t>(v) * ids.width + u];
      if (id == 0) continue;
      ++area[id];
      auto [it, fresh] = box.try_emplace(id, std::array<int, 4>{u, v, u, v});
      if (!fresh) it->second = {std::min(it->second[0], u), std::min(it->second[1], v), std::max(it->second[2], u),
                                std::max(it->second[3], v)};
    }
  ASSERT_EQ(area.size(), regions.rows.size());  // ids 1..K, no other
  for (std::size_t i = 0; i < regions.rows.size(); ++i) {
    const int id = static_cast<int>(regions.value(i, "rank"));
    ASSERT_EQ(id, static_cast<int>(i + 1));
    EXPECT_EQ(area[id], static_cast<std::size_t>(regions.value(i, "area_columns"))) << id;
    EXPECT_EQ(box[id], (std::array<int, 4>{static_cast<int>(regions.value(i, "min_u")),
                                           static_cast<int>(regions.value(i, "min_v")),
                                           static_cast<int>(regions.value(i, "max_u")),
                                           static_cast<int>(regions.value(i, "max_v"))}))
        << id;
    EXPECT_EQ(ids.values[pixel(regions, i, "peak_u", "peak_v")], id);
    EXPECT_EQ(ids.values[pixel(regions, i, "centre_u", "centre_v")], id);
  }
}

// depth_mm.png: the surface depth of surface.pcd in millimetres, 0 where unknown; readable as a depth
// image by the tools themselves.
TEST_F(ToolMasksAndImages, DepthMmPngIsTheSurfaceDepthInMillimetres) {
  const fs::path out = dir_ / "out";
  const ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-sample -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const occ_improve::DepthImage16 mm = occ_improve::read_depth_image16((out / "depth_mm.png").string());
  pcl::PointCloud<occ_improve::PointImprovement> surface;
  ASSERT_EQ(pcl::io::loadPCDFile((out / "surface.pcd").string(), surface), 0);
  ASSERT_EQ(mm.values.size(), surface.size());
  std::size_t known = 0;
  for (std::size_t i = 0; i < surface.size(); ++i) {
    const double expected = std::round(surface[i].surface_depth * 1000.0);
    ASSERT_EQ(mm.values[i], static_cast<std::uint16_t>(expected)) << "pixel " << i;
    known += mm.values[i] != 0;
  }
  EXPECT_GT(known, surface.size() / 2);
  const auto [lo, hi] = std::minmax_element(mm.values.begin(), mm.values.end());
  EXPECT_EQ(*lo, 0);
  EXPECT_GT(*hi, 4000);  // the wall at 4.2 m, the recess at 6.5 m
}

}  // namespace
