// The per-file batch mode (-input_dir DIR -output_dir OUTDIR, issue 24's PCL habit), run as a user runs
// the tools: each frame file of a folder on its own into OUTDIR/<stem>/, with the values of each folder
// equal to a run of the tool on that file alone; failures named and counted, other files counted as
// skipped; outputs inside the inputs refused; per-file folders under the usual never-overwrite rule;
// Ctrl-C obeyed between files, the files done kept.
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/sample_scene.hpp"
#include "support/csv_table.hpp"
#include "support/temp_folder.hpp"
#include "support/tool_run.hpp"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;

using ToolRun = test::ToolStreams;
using test::file_contents;

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class Batch : public test::TempFolderTest {
protected:
  ToolRun run(const std::string& executable, const std::string& arguments) {
    return test::run_tool_in(folder_, executable, arguments);
  }
  // The built-in scene with noise seed `seed` (frames of one view that differ in their noise), as an
  // organized PCD in `folder`.
  void write_pcd(const std::string& folder, const std::string& name, std::uint32_t seed) {
    sample::SceneOptions options;
    options.seed = seed;
    const sample::SampleFrame scene = sample::generate_scene(options);
    fs::create_directories(folder_ / folder);
    ASSERT_EQ(pcl::io::savePCDFileBinary((folder_ / folder / name).string(),
                                         organized_cloud(scene.points(), scene.intrinsics.width, scene.intrinsics.height)),
              0);
  }
  // The scene as a 16-bit millimetre depth PNG with its camera-intrinsics.txt beside it (the 7-Scenes layout).
  void write_depth_png(const std::string& folder, const std::string& name, std::uint32_t seed) {
    sample::SceneOptions options;
    options.seed = seed;
    const sample::SampleFrame scene = sample::generate_scene(options);
    Image16 depth{scene.intrinsics.width, scene.intrinsics.height, {}};
    for (float z : scene.depth_m) depth.pixels.push_back(static_cast<std::uint16_t>(std::lround(z * 1000.0f)));
    write_png((folder_ / folder / name).string(), depth);
    const PinholeIntrinsics& k = scene.intrinsics;
    std::ofstream(folder_ / folder / "camera-intrinsics.txt")
        << k.fx << " 0 " << k.cx << "\n0 " << k.fy << " " << k.cy << "\n0 0 1\n";
  }
  // regions.csv of a batch folder and of the tool run on the file alone: the same rows, value for value.
  void expect_same_regions(const fs::path& batch_folder, const std::string& input, const std::string& flags) {
    const std::string alone = "alone_" + batch_folder.filename().string();
    const ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, input + " " + flags + " -o " + alone);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const test::CsvTable batch = test::read_csv(batch_folder / "regions.csv"), single = test::read_csv(folder_ / alone / "regions.csv");
    ASSERT_FALSE(batch.rows.empty()) << batch_folder;
    EXPECT_EQ(batch.header, single.header);
    EXPECT_EQ(batch.rows, single.rows) << batch_folder;
    EXPECT_GT(batch.value(0, "summed_improvement"), 0.0);
  }
};

// The case: a folder of three generated frames (two PCDs, one depth PNG with its camera file),
// one corrupt PCD, a depth image of the wrong size and one unrelated text file. Three folders whose regions equal the tool on each file
// alone; the corrupt and the wrong-size file named on stderr and counted; the text and intrinsics files counted as skipped;
// exit 1 because files failed.
TEST_F(Batch, EachFrameFileGetsTheFolderItsOwnRunWritesAndFailuresAreNamedAndCounted) {
  write_pcd("in", "frame_a.pcd", 1);
  write_pcd("in", "frame_b.pcd", 7);
  write_depth_png("in", "frame_c.png", 3);
  std::ofstream(folder_ / "in" / "broken.pcd") << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nnot a header\n";
  std::ofstream(folder_ / "in" / "notes.txt") << "taken on Tuesday\n";
  write_png((folder_ / "in" / "tiny.png").string(), Image16{4, 3, std::vector<std::uint16_t>(12, 1000)});  // not 640 x 480

  const ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-input_dir in -output_dir out -depth_encoding mm -q");
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_EQ(count_of(r.err, "error: "), 2u) << r.err;
  EXPECT_NE(r.err.find("broken.pcd"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tiny.png"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("processed 3, failed 2 (broken.pcd, tiny.png), skipped 2 (camera-intrinsics.txt, notes.txt)"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(folder_ / "out" / "broken"));
  EXPECT_FALSE(fs::exists(folder_ / "out" / "tiny"));
  for (const char* stem : {"frame_a", "frame_b", "frame_c"}) {
    EXPECT_TRUE(fs::is_regular_file(folder_ / "out" / stem / ".occ_improve_output")) << stem;
    EXPECT_TRUE(fs::is_regular_file(folder_ / "out" / stem / "improvement.png")) << stem;
  }
  expect_same_regions(folder_ / "out" / "frame_a", "in/frame_a.pcd", "-depth_encoding mm");
  expect_same_regions(folder_ / "out" / "frame_b", "in/frame_b.pcd", "-depth_encoding mm");
  expect_same_regions(folder_ / "out" / "frame_c", "in/frame_c.png", "-depth_encoding mm");
  // Frames of other noise give other regions: the folders are not copies of one run.
  EXPECT_NE(test::read_csv(folder_ / "out" / "frame_a" / "regions.csv").rows,
            test::read_csv(folder_ / "out" / "frame_b" / "regions.csv").rows);
}

// Outputs inside the inputs, and the batch flags mixed with the fusion's, are refused in one line before
// any work.
TEST_F(Batch, OutputInsideTheInputsAndMixedFlagsAreRefusedBeforeAnyWork) {
  write_pcd("in", "frame_a.pcd", 1);
  fs::create_directories(folder_ / "empty");
  std::ofstream(folder_ / "empty" / "notes.txt") << "nothing to map\n";
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"-input_dir empty -output_dir out", "holds no frame file (.pcd .ply .png .pgm .tif .tiff); skipped: notes.txt"},
      {"-input_dir missing -output_dir out", "is not a folder"},
      {"-input_dir in -output_dir in/out", "inside -input_dir"},
      {"-input_dir in -output_dir in", "inside -input_dir"},
      {"-input_dir in -output_dir out in/frame_a.pcd", "not both"},
      {"-input_dir in -output_dir out -o other", "-o cannot be given"},
      {"-input_dir in -output_dir out -save m.occmap", "-save cannot be given"},
      {"-input_dir in", "needs -output_dir"},
      {"-output_dir out in/frame_a.pcd", "give -input_dir"},
  };
  for (const auto& [arguments, why] : refused) {
    const ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, arguments);
    EXPECT_EQ(r.exit_code, 1) << arguments;
    EXPECT_EQ(count_of(r.err, "\n"), 1u) << arguments << ": " << r.err;
    EXPECT_NE(r.err.find(why), std::string::npos) << arguments << ": " << r.err;
    EXPECT_EQ(r.out.find("[1/"), std::string::npos) << arguments << ": " << r.out;
  }
  EXPECT_FALSE(fs::exists(folder_ / "in" / "out"));
  EXPECT_FALSE(fs::exists(folder_ / "in" / "frame_a"));
  EXPECT_FALSE(fs::exists(folder_ / "out"));
  EXPECT_FALSE(fs::exists(folder_ / "other"));
}

// A second run over its own outputs replaces them; a per-file folder holding a file the tool did not write
// refuses the whole batch before any work (naming -overwrite), and -overwrite writes into it beside that file.
TEST_F(Batch, PerFileFoldersFollowTheNeverOverwriteRule) {
  write_pcd("in", "frame_a.pcd", 1);
  write_pcd("in", "frame_b.pcd", 2);
  ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-input_dir in -output_dir out -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("processed 2, failed 0, skipped 0"), std::string::npos) << r.out;
  const test::CsvTable first = test::read_csv(folder_ / "out" / "frame_a" / "regions.csv");

  r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-input_dir in -output_dir out -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(test::read_csv(folder_ / "out" / "frame_a" / "regions.csv").rows, first.rows);

  std::ofstream(folder_ / "out" / "frame_b" / "mine.txt") << "a user's note\n";
  fs::remove(folder_ / "out" / "frame_a" / "regions.csv");  // would come back if frame_a were processed
  r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-input_dir in -output_dir out -q");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(count_of(r.err, "\n"), 1u) << r.err;
  EXPECT_NE(r.err.find("-overwrite"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-output_dir, the folder of 'in/frame_b.pcd'"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("[1/"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(folder_ / "out" / "frame_a" / "regions.csv"));
  EXPECT_EQ(file_contents(folder_ / "out" / "frame_b" / "mine.txt"), "a user's note\n");

  r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-input_dir in -output_dir out -q -overwrite");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(file_contents(folder_ / "out" / "frame_b" / "mine.txt"), "a user's note\n");
  EXPECT_EQ(test::read_csv(folder_ / "out" / "frame_a" / "regions.csv").rows, first.rows);
  EXPECT_FALSE(test::read_csv(folder_ / "out" / "frame_b" / "regions.csv").rows.empty());
}

// A dataset folder's colour images are not depth frames: skipped and counted, not failed.
TEST_F(Batch, ADatasetFoldersColourImagesAreSkipped) {
  fs::create_directories(folder_ / "in");
  write_depth_png("in", "frame-000000.depth.png", 1);
  write_png((folder_ / "in" / "frame-000000.color.png").string(), Image{4, 3, 3, std::vector<std::uint8_t>(36, 90)});
  const ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-input_dir in -output_dir out -depth_encoding mm -q");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("processed 1, failed 0, skipped 2 (camera-intrinsics.txt, frame-000000.color.png)"),
            std::string::npos)
      << r.out;
  expect_same_regions(folder_ / "out" / "frame-000000.depth", "in/frame-000000.depth.png", "-depth_encoding mm");
}

// Open3D's sample layout, TUM_depth.png beside TUM_color.png: the colour image failed as a depth frame and
// the batch exited 1. Images that name their depth make the others colour, as -depth_dir reads a folder.
TEST_F(Batch, ImagesNamedDepthMakeTheOthersColour) {
  fs::create_directories(folder_ / "in");
  write_depth_png("in", "TUM_depth.png", 1);
  write_png((folder_ / "in" / "TUM_color.png").string(), Image{4, 3, 3, std::vector<std::uint8_t>(36, 90)});
  const ToolRun r = run(OCC_IMPROVE_MAP_EXECUTABLE, "-input_dir in -output_dir out -depth_encoding mm -q");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("processed 1, failed 0, skipped 2 (TUM_color.png, camera-intrinsics.txt)"), std::string::npos)
      << r.out;
  expect_same_regions(folder_ / "out" / "TUM_depth", "in/TUM_depth.png", "-depth_encoding mm");
}

// occ_segment and occ_plan take the same flags (tool_support's plumbing): one folder per file with the
// values of the tool run on that file alone.
TEST_F(Batch, SegmentAndPlanRunPerFileToo) {
  write_pcd("in", "frame_a.pcd", 1);
  write_pcd("in", "frame_b.pcd", 5);
  ToolRun r = run(OCC_SEGMENT_EXECUTABLE, "-input_dir in -output_dir seg");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run(OCC_PLAN_EXECUTABLE, "-input_dir in -output_dir plan -budget 2000");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* stem : {"frame_a", "frame_b"}) {
    const std::string input = std::string("in/") + stem + ".pcd";
    r = run(OCC_SEGMENT_EXECUTABLE, input + " -o seg_alone");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const test::CsvTable batch = test::read_csv(folder_ / "seg" / stem / "segments.csv");
    ASSERT_FALSE(batch.rows.empty()) << stem;
    EXPECT_EQ(batch.rows, test::read_csv(folder_ / "seg_alone" / "segments.csv").rows) << stem;
    r = run(OCC_PLAN_EXECUTABLE, input + " -budget 2000 -o plan_alone");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const test::CsvTable shot = test::read_csv(folder_ / "plan" / stem / "shot_rays.csv");
    EXPECT_FALSE(shot.rows.empty()) << stem;
    EXPECT_EQ(shot.rows, test::read_csv(folder_ / "plan_alone" / "shot_rays.csv").rows) << stem;
  }
}

// Ctrl-C between files: exit 130, the folders of the files done complete, the rest not started, nothing
// staged left behind.
TEST_F(Batch, InterruptKeepsTheFilesDone) {
  for (int i = 0; i < 8; ++i) write_pcd("in", "frame_" + std::to_string(i) + ".pcd", static_cast<std::uint32_t>(i + 1));
  const std::string command = "cd " + folder_.string() + " && (" + std::string(OCC_IMPROVE_MAP_EXECUTABLE) +
                              " -input_dir in -output_dir out -q > stdout.log 2> stderr.log & echo $! > pid; wait $!; "
                              "echo $? > rc.tmp; mv rc.tmp rc) > /dev/null 2>&1 &";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const fs::path done = folder_ / "out" / "frame_0" / "regions.csv";
  for (int i = 0; i < 6000 && !fs::exists(done); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(fs::exists(done));
  while (!fs::exists(folder_ / "pid")) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_FALSE(fs::exists(folder_ / "rc")) << "finished before the signal";
  ::kill(static_cast<pid_t>(std::stol(file_contents(folder_ / "pid"))), SIGINT);
  for (int i = 0; i < 3000 && !fs::exists(folder_ / "rc"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(fs::exists(folder_ / "rc"));
  EXPECT_EQ(std::stoi(file_contents(folder_ / "rc")), 130) << file_contents(folder_ / "stderr.log");
  EXPECT_NE(file_contents(folder_ / "stdout.log").find("batch interrupted at"), std::string::npos);
  EXPECT_FALSE(test::read_csv(done).rows.empty());
  EXPECT_FALSE(fs::exists(folder_ / "out" / "frame_7"));
  std::size_t folders = 0;
  for (const auto& entry : fs::directory_iterator(folder_ / "out")) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
    if (entry.is_directory()) {
      ++folders;
      EXPECT_TRUE(fs::exists(entry.path() / "regions.csv")) << entry.path();
    }
  }
  EXPECT_GE(folders, 1u);
  EXPECT_LT(folders, 8u);
}

}  // namespace
}  // namespace occ_improve
