// Saving and loading maps (map_io.hpp): exact round trips on generated scenes, atomic saves, and every
// kind of bad file refused with a typed error.
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/maps/surface.hpp"
#include "support/lidar_scene.hpp"
#include "support/log_depth_binning.hpp"
#include "support/map_compare.hpp"
#include "occ_improve/geometry/spherical_binning.hpp"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;

// A scratch folder per test, removed afterwards.
class MapIo : public ::testing::Test {
protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    folder_ = fs::temp_directory_path() / (std::string("occ_map_io_") + info->name() + "_" +
                                           std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }
  std::string file(const std::string& name) const { return (folder_ / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder_)) names.push_back(e.path().filename().string());
    return names;
  }
  fs::path folder_;
};

std::vector<char> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The checksum exactly as docs/MAP_FORMAT.md defines it (written from the document, not the library).
std::uint64_t documented_checksum(const std::vector<char>& bytes, std::size_t size) {
  std::uint64_t h = 14695981039346656037ull;
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, bytes.data() + i, 8);
    h = (h ^ word) * 1099511628211ull;
  }
  for (; i < size; ++i) h = (h ^ static_cast<unsigned char>(bytes[i])) * 1099511628211ull;
  return h;
}

void reseal(std::vector<char>& bytes) {
  const std::uint64_t h = documented_checksum(bytes, bytes.size() - 8);
  std::memcpy(bytes.data() + bytes.size() - 8, &h, 8);
}

// Surface and improvement maps of two grids, bit for bit (the maps a loaded map must reproduce).
// The FormatError a map of these bytes (resealed: a consistent checksum over them) gets when loaded from
// `path`; "" when it loads.
std::string format_error_loading(const std::string& path, std::vector<char> bytes) {
  reseal(bytes);
  write_bytes(path, bytes);
  try {
    load_map(path);
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

void expect_same_maps(const ColumnGrid& a, const ColumnGrid& b, const SensorModelParams& model) {
  const SurfaceMap sa = compute_surface(a), sb = compute_surface(b);
  test::expect_same_surface(sa, sb);
  const SensorModel m(model);
  test::expect_same_improvement(compute_improvement(a.geometry(), m, sa), compute_improvement(b.geometry(), m, sb));
}

// The sample scene's frames, generated once for the whole test program.
const std::vector<std::vector<Eigen::Vector3f>>& sample_frames() {
  static const auto frames = [] {
    std::vector<std::vector<Eigen::Vector3f>> points;
    for (const auto& frame : sample::generate_sequence(2)) points.push_back(frame.points());
    return points;
  }();
  return frames;
}

// The paper preset at 40 x 30 x 64 bins: a small grid for the records and poses saved beside it.
SensorPreset small_paper_preset() {
  SensorPreset preset = kinect_v1_paper();
  preset.geometry.azimuth_bins = 40;
  preset.geometry.elevation_bins = 30;
  preset.geometry.depth_bins = 64;
  return preset;
}

ColumnGrid sample_grid(const SensorPreset& preset, const GridOptions& options, int frames = 1) {
  ColumnGrid grid{GridGeometry(preset.geometry), options};
  const SensorModel model(preset.model);
  for (int f = 0; f < frames; ++f) insert_points(grid, model, PointSpan::from(sample_frames()[static_cast<std::size_t>(f)]));
  return grid;
}

TEST_F(MapIo, PaperPresetSampleFrameRoundTripsBitForBit) {
  const SensorPreset preset = kinect_v1_paper();
  const ColumnGrid grid = sample_grid(preset, {});
  ASSERT_GT(grid.touched_column_count(), 100000u);
  save_map(file("frame.occmap"), grid, preset.model);
  const LoadedMap loaded = load_map(file("frame.occmap"));
  EXPECT_TRUE(test::same_model(loaded.model, preset.model));
  test::expect_identical(grid, loaded.grid);
  expect_same_maps(grid, loaded.grid, preset.model);
  EXPECT_EQ(entries(), std::vector<std::string>{"frame.occmap"}) << "no temporary file may be left behind";
}

TEST_F(MapIo, MappingContinuedFromASavedMapEqualsUninterruptedMapping) {
  const SensorPreset preset = kinect_v1_paper();
  Mapper uninterrupted(preset);
  uninterrupted.insert(PointSpan::from(sample_frames()[0]));
  save_map(file("first.occmap"), uninterrupted.grid(), uninterrupted.model().params());
  LoadedMap loaded = load_map(file("first.occmap"));
  Mapper resumed(std::move(loaded.grid), SensorModel(loaded.model));
  test::expect_same_surface(uninterrupted.surface(), resumed.surface());
  test::expect_same_improvement(uninterrupted.improvement(), resumed.improvement());

  uninterrupted.insert(PointSpan::from(sample_frames()[1]));
  resumed.insert(PointSpan::from(sample_frames()[1]));
  test::expect_identical(uninterrupted.grid(), resumed.grid());
  test::expect_same_surface(uninterrupted.surface(), resumed.surface());
  test::expect_same_improvement(uninterrupted.improvement(), resumed.improvement());
}

TEST_F(MapIo, PixelNativePresetRoundTripsWithItsCamera) {
  const PinholeIntrinsics k{575.8, 576.0, 321.0, 238.5, 640, 480};
  const SensorPreset preset = kinect_v1(k);
  const ColumnGrid grid = sample_grid(preset, GridOptions{});
  save_map(file("pinhole.occmap"), grid, preset.model);
  const LoadedMap loaded = load_map(file("pinhole.occmap"));
  EXPECT_EQ(loaded.grid.geometry().binning(), AngularBinning::pinhole);
  EXPECT_EQ(loaded.grid.geometry().params().camera, k);
  EXPECT_TRUE(loaded.grid.geometry() == grid.geometry());
  EXPECT_EQ(loaded.model.sigma_u_px, preset.model.sigma_u_px);
  expect_same_maps(grid, loaded.grid, preset.model);
}

TEST_F(MapIo, SphericalPresetKeepsItsObservableColumns) {
  const SensorPreset preset = kinect_v1_spherical();
  const ColumnGrid grid = sample_grid(preset, GridOptions{});
  save_map(file("spherical.occmap"), grid, preset.model);
  const LoadedMap loaded = load_map(file("spherical.occmap"));
  EXPECT_EQ(loaded.grid.geometry().observable_count(), grid.geometry().observable_count());
  EXPECT_LT(loaded.grid.geometry().observable_count(), loaded.grid.geometry().column_count());
}

TEST_F(MapIo, ExactModeInverseDepthPresetRoundTrips) {
  SensorPreset preset = kinect_v1();
  preset.geometry.depth_bins = 256;
  GridOptions options;
  options.mode = UpdateMode::exact;
  const ColumnGrid grid = sample_grid(preset, options, 2);
  save_map(file("exact.occmap"), grid, preset.model);
  const LoadedMap loaded = load_map(file("exact.occmap"));
  EXPECT_EQ(loaded.grid.options().mode, UpdateMode::exact);
  EXPECT_EQ(loaded.grid.geometry().params().depth_binning, DepthBinning::inverse_depth);
  EXPECT_TRUE(test::same_model(loaded.model, preset.model));
  test::expect_identical(grid, loaded.grid);
  expect_same_maps(grid, loaded.grid, preset.model);
}

TEST_F(MapIo, OctomapClampingAndEmptyGridRoundTrip) {
  SensorPreset preset = kinect_v1_paper();
  preset.geometry.azimuth_bins = 64;
  preset.geometry.elevation_bins = 48;
  const ColumnGrid empty{GridGeometry(preset.geometry), GridOptions::octomap_clamping()};
  save_map(file("empty.occmap"), empty, preset.model);
  const LoadedMap loaded = load_map(file("empty.occmap"));
  EXPECT_EQ(loaded.grid.touched_column_count(), 0u);
  EXPECT_EQ(loaded.grid.options().probability_min, 0.1192);
  EXPECT_EQ(loaded.grid.options().probability_max, 0.971);
  test::expect_identical(empty, loaded.grid);
}

// Resaving replaces a map. save_map polled no stop (a 1.7 GB exact-mode map was written whole, a Ctrl-C seen
// 1-8 s later): a stop requested before the save cancels it, leaving the previous map and no temporary.
TEST_F(MapIo, ResavingReplacesAMapAndACancelledSaveKeepsIt) {
  SensorPreset preset = kinect_v1_paper();
  preset.geometry.azimuth_bins = 64;
  preset.geometry.elevation_bins = 48;
  const ColumnGrid empty{GridGeometry(preset.geometry)};
  save_map(file("map.occmap"), empty, preset.model);
  const ColumnGrid full = sample_grid(preset, {});
  ASSERT_GT(full.touched_column_count(), 0u);
  request_stop(2);
  EXPECT_THROW(save_map(file("map.occmap"), full, preset.model), Cancelled);
  clear_stop_request();
  test::expect_identical(empty, load_map(file("map.occmap")).grid);
  EXPECT_EQ(entries().size(), 1u);
  save_map(file("map.occmap"), full, preset.model);
  test::expect_identical(full, load_map(file("map.occmap")).grid);
  EXPECT_EQ(entries().size(), 1u);
}

class BadMapFile : public MapIo {
protected:
  // A small valid map (80 x 60 columns), saved once for the whole suite.
  static void SetUpTestSuite() {
    SensorPreset preset = kinect_v1_paper();
    preset.geometry.azimuth_bins = 80;
    preset.geometry.elevation_bins = 60;
    preset.geometry.depth_bins = 128;
    const ColumnGrid grid = sample_grid(preset, {});
    touched_ = grid.touched_column_count();
    // One file per process: ctest runs the tests of this suite in parallel processes.
    const std::string path =
        (fs::temp_directory_path() / ("occ_map_io_good_suite_" + std::to_string(::getpid()) + ".occmap")).string();
    save_map(path, grid, preset.model);
    good_ = read_bytes(path);
    fs::remove(path);
  }
  void SetUp() override {
    MapIo::SetUp();
    ASSERT_GT(touched_, 1000u);
    write_bytes(file("good.occmap"), good_);
  }
  // Loads `bytes` and returns the FormatError message ("" when no FormatError was thrown).
  std::string format_error_of(const std::vector<char>& bytes) {
    write_bytes(file("bad.occmap"), bytes);
    try {
      load_map(file("bad.occmap"));
    } catch (const FormatError& e) {
      return e.what();
    }
    return "";
  }
  static inline std::vector<char> good_;
  static inline std::size_t touched_ = 0;
};

// Offsets from docs/MAP_FORMAT.md.
constexpr std::size_t kMarkerOffset = 8, kVersionOffset = 12, kAzimuthBinsOffset = 16;
// geometry 64 + binning and camera 48, model 64, options 28, column count 8.
constexpr std::size_t kFirstColumnOffset = 16 + 64 + 48 + 64 + 28 + 8;

// The same map (saved without a return record) in format version 2: without the return record's
// flag (the 4 bytes before the checksum).
std::vector<char> as_version_2(const std::vector<char>& v3) {
  std::vector<char> v2(v3.begin(), v3.end() - 12);
  v2.insert(v2.end(), v3.end() - 8, v3.end());
  const std::uint32_t version = 2;
  std::memcpy(v2.data() + kVersionOffset, &version, 4);
  reseal(v2);
  return v2;
}

// The same map in format version 1: without the binning and camera (offsets 80-127) and the pixel
// sigmas (176-191), as docs/MAP_FORMAT.md describes it.
std::vector<char> as_version_1(const std::vector<char>& v3) {
  const std::vector<char> v2 = as_version_2(v3);
  std::vector<char> v1(v2.begin(), v2.begin() + 80);
  v1.insert(v1.end(), v2.begin() + 128, v2.begin() + 176);
  v1.insert(v1.end(), v2.begin() + 192, v2.end());
  const std::uint32_t version = 1;
  std::memcpy(v1.data() + kVersionOffset, &version, 4);
  reseal(v1);
  return v1;
}

TEST_F(BadMapFile, VersionOneMapsStillLoad) {
  write_bytes(file("v1.occmap"), as_version_1(good_));
  const LoadedMap old = load_map(file("v1.occmap"));
  const LoadedMap current = load_map(file("good.occmap"));
  EXPECT_EQ(old.grid.geometry().binning(), AngularBinning::spherical);
  EXPECT_FALSE(old.grid.geometry().params().camera.has_value());
  EXPECT_EQ(old.grid.touched_column_count(), touched_);
  expect_same_maps(old.grid, current.grid, current.model);
}

TEST_F(BadMapFile, VersionTwoMapsLoadWithAnEmptyReturnRecord) {
  write_bytes(file("v2.occmap"), as_version_2(good_));
  const LoadedMap old = load_map(file("v2.occmap"));
  EXPECT_TRUE(old.returns.empty());
  EXPECT_EQ(old.returns.width(), 80);
  EXPECT_EQ(old.returns.height(), 60);
  expect_same_maps(old.grid, load_map(file("good.occmap")).grid, old.model);
}

TEST_F(BadMapFile, IntactFileLoads) { EXPECT_NO_THROW(load_map(file("good.occmap"))); }

TEST_F(BadMapFile, FlippedBitIsRefusedByTheChecksum) {
  for (std::size_t at : {kAzimuthBinsOffset + 4, good_.size() / 2, good_.size() - 9}) {
    auto bytes = good_;
    bytes[at] = static_cast<char>(bytes[at] ^ 0x10);
    EXPECT_NE(format_error_of(bytes).find("checksum"), std::string::npos) << "byte " << at;
  }
}

TEST_F(BadMapFile, TruncatedFileIsRefused) {
  for (std::size_t size : {std::size_t{0}, std::size_t{5}, std::size_t{20}, good_.size() / 2, good_.size() - 1}) {
    const std::vector<char> bytes(good_.begin(), good_.begin() + static_cast<std::ptrdiff_t>(size));
    EXPECT_FALSE(format_error_of(bytes).empty()) << "size " << size;
  }
}

TEST_F(BadMapFile, OtherVersionIsRefusedNamingTheVersion) {
  auto bytes = good_;
  const std::uint32_t version = kMapFormatVersion + 1;
  std::memcpy(bytes.data() + kVersionOffset, &version, 4);
  reseal(bytes);
  EXPECT_NE(format_error_of(bytes).find("version " + std::to_string(version)), std::string::npos);
}

TEST_F(BadMapFile, OtherByteOrderIsRefused) {
  auto bytes = good_;
  std::swap(bytes[kMarkerOffset], bytes[kMarkerOffset + 3]);
  std::swap(bytes[kMarkerOffset + 1], bytes[kMarkerOffset + 2]);
  reseal(bytes);
  EXPECT_NE(format_error_of(bytes).find("byte order"), std::string::npos);
}

TEST_F(BadMapFile, FileThatIsNotAMapIsRefused) {
  const std::string text = "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
  EXPECT_NE(format_error_of(std::vector<char>(text.begin(), text.end())).find("not an occ_improve map"),
            std::string::npos);
}

TEST_F(BadMapFile, ConsistentChecksumButInvalidContentsAreRefused) {
  {  // a geometry the library refuses
    auto bytes = good_;
    const std::int32_t zero_bins = 0;
    std::memcpy(bytes.data() + kAzimuthBinsOffset, &zero_bins, 4);
    reseal(bytes);
    EXPECT_NE(format_error_of(bytes).find("invalid geometry"), std::string::npos);
  }
  {  // the first column record pointing outside the grid
    auto bytes = good_;
    const std::uint32_t outside = 80 * 60;
    std::memcpy(bytes.data() + kFirstColumnOffset, &outside, 4);
    reseal(bytes);
    EXPECT_NE(format_error_of(bytes).find("outside the grid"), std::string::npos);
  }
  {  // a window running past the depth bins
    auto bytes = good_;
    const std::uint32_t too_long = 129;
    std::memcpy(bytes.data() + kFirstColumnOffset + 12, &too_long, 4);
    reseal(bytes);
    EXPECT_NE(format_error_of(bytes).find("runs past"), std::string::npos);
  }
  {  // a log-odds value beyond the clamp
    auto bytes = good_;
    const float beyond = 100.0f;
    std::memcpy(bytes.data() + kFirstColumnOffset + 16, &beyond, 4);
    reseal(bytes);
    EXPECT_NE(format_error_of(bytes).find("out of range"), std::string::npos);
  }
}

// A 172-byte map asking for 2^31 - 1 depth bins allocated 2 x 16 GiB before any check, and the cap it was
// checked against came from the file itself.
TEST_F(BadMapFile, SizesAreCheckedAgainstTheCallersCapBeforeAllocating) {
  auto bytes = good_;
  const std::int32_t huge_bins = 2147483647;
  std::memcpy(bytes.data() + kAzimuthBinsOffset + 8, &huge_bins, 4);
  const std::uint64_t file_cap = ~std::uint64_t{0};  // a forged file raising its own cap
  std::memcpy(bytes.data() + kFirstColumnOffset - 16, &file_cap, 8);
  reseal(bytes);
  write_bytes(file("huge.occmap"), bytes);
  try {
    load_map(file("huge.occmap"));
    FAIL() << "2^31 - 1 depth bins must exceed the default cap";
  } catch (const ResourceLimit& e) {
    EXPECT_NE(std::string(e.what()).find("huge.occmap"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2147483647"), std::string::npos) << e.what();
  }
  // The intact map: refused under a small cap of the caller's, loaded with the caller's cap otherwise.
  EXPECT_THROW(load_map(file("good.occmap"), 1 << 20), ResourceLimit);
  const std::size_t cap = std::size_t{64} << 20;
  EXPECT_EQ(load_map(file("good.occmap"), cap).grid.options().memory_cap_bytes, cap);
}

// A 172-byte map claiming 10000 x 10000 columns of 16 bins passed the old cap of 8 GiB (its voxels:
// 6.4 GB) and the run then took 7.2 GB in dense per-column maps; one claiming 2^27 depth bins of one
// column took 4.2 GB in per-bin tables. The worst case now counts both, and both are refused under the
// old 8 GiB, naming the file, the claimed grid and the cap.
TEST_F(BadMapFile, ClaimedColumnsAndDepthBinsCountTheirDenseMapsAndTables) {
  const std::size_t old_default_cap = std::size_t{8} << 30;
  const auto refusal = [&](std::int32_t azimuth, std::int32_t elevation, std::int32_t depth) -> std::string {
    auto bytes = good_;
    const std::int32_t bins[] = {azimuth, elevation, depth};
    std::memcpy(bytes.data() + kAzimuthBinsOffset, bins, sizeof bins);
    reseal(bytes);
    write_bytes(file("claims.occmap"), bytes);
    try {
      load_map(file("claims.occmap"), old_default_cap);
    } catch (const ResourceLimit& e) {
      return e.what();
    }
    return "";
  };
  for (const std::string& e : {refusal(10000, 10000, 16), refusal(1, 1, 134217728)}) {
    EXPECT_NE(e.find("claims.occmap"), std::string::npos) << e;
    EXPECT_NE(e.find("above memory_cap_bytes = 8192 MiB"), std::string::npos) << e;
  }
  EXPECT_NE(refusal(10000, 10000, 16).find("grid of 10000 x 10000 x 16 bins"), std::string::npos);
  // 100 bytes of maps per column and more: at least 1e8 x (16 x 4 + 100) bytes.
  GeometryParams g;
  g.azimuth_bins = g.elevation_bins = 10000;
  g.depth_bins = 16;
  EXPECT_GT(grid_worst_case_bytes(g), 1e8 * (16 * 4 + 100));
  // The default cap is half of the machine's physical memory.
  const double physical = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
  EXPECT_NEAR(static_cast<double>(default_memory_cap_bytes()), physical / 2, 4096.0);
  EXPECT_EQ(GridOptions{}.memory_cap_bytes, default_memory_cap_bytes());
}

TEST_F(MapIo, ReturnRecordRoundTripsAndABadOneIsRefused) {
  const SensorPreset preset = small_paper_preset();
  const ColumnGrid grid = sample_grid(preset, {});
  ReturnRecord returns = ReturnRecord::for_grid(40, 30);
  returns.record_shot({3, 3, 500, 1199}, {0, 1, 1, 0});
  save_map(file("returns.occmap"), grid, preset.model, returns);
  const LoadedMap loaded = load_map(file("returns.occmap"));
  EXPECT_EQ(loaded.returns.asked(), returns.asked());
  EXPECT_EQ(loaded.returns.returned(), returns.returned());
  EXPECT_EQ(loaded.returns.asked_nearby(), returns.asked_nearby());
  EXPECT_EQ(loaded.returns.total_returned(), 2u);
  // A record of another grid is refused before anything is written.
  EXPECT_THROW(save_map(file("other.occmap"), grid, preset.model, ReturnRecord::for_grid(40, 31)), InvalidInput);
  EXPECT_FALSE(fs::exists(file("other.occmap")));
  // More returns than asks (a consistent checksum over an inconsistent record): a FormatError naming it.
  auto bytes = read_bytes(file("returns.occmap"));
  const std::size_t last_returned = bytes.size() - 8 - 4;  // column 1199: 1 ask, 0 returns
  const std::uint32_t two = 2;
  std::memcpy(bytes.data() + last_returned, &two, 4);
  const std::string error = format_error_loading(file("bad.occmap"), bytes);
  EXPECT_NE(error.find("column 1199"), std::string::npos) << error;
}

// Frames with poses of their own could not be added to a loaded map: it kept no pose, so the tools took
// the new frames' first one as the map's view (a 7-Scenes chain: 68 % of the pixels off by > 20 mm). A map
// saved with its sensor frame's pose is version 5 and gives it back; one without stays version 3, byte for
// byte the map it was before.
TEST_F(MapIo, PoseRoundTripsAsVersionFiveAndAMapWithoutOneStaysVersionThree) {
  const SensorPreset preset = small_paper_preset();
  const ColumnGrid grid = sample_grid(preset, {});
  ReturnRecord returns = ReturnRecord::for_grid(40, 30);
  returns.record_shot({3, 500}, {1, 0});
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(1.5, -0.25, 3.0);
  save_map(file("posed.occmap"), grid, preset.model, returns, pose);
  save_map(file("plain.occmap"), grid, preset.model, returns);
  const auto version_of = [&](const std::string& name) {
    std::uint32_t v;
    std::memcpy(&v, read_bytes(file(name)).data() + 12, 4);
    return v;
  };
  EXPECT_EQ(version_of("posed.occmap"), 5u);
  EXPECT_EQ(version_of("plain.occmap"), 3u);
  const LoadedMap loaded = load_map(file("posed.occmap"));
  ASSERT_TRUE(loaded.world_from_sensor.has_value());
  EXPECT_TRUE(loaded.world_from_sensor->matrix().isApprox(pose.matrix(), 1e-12)) << loaded.world_from_sensor->matrix();
  EXPECT_EQ(loaded.returns.asked(), returns.asked());
  expect_same_maps(grid, loaded.grid, preset.model);
  EXPECT_FALSE(load_map(file("plain.occmap")).world_from_sensor.has_value());
  // Not a rigid motion: refused before anything is written.
  Eigen::Isometry3d scaled = pose;
  scaled.linear() *= 1.1;
  EXPECT_THROW(save_map(file("scaled.occmap"), grid, preset.model, returns, scaled), InvalidParameter);
  EXPECT_FALSE(fs::exists(file("scaled.occmap")));
  // A stored pose that is no rotation (a consistent checksum over it): a FormatError naming the pose.
  auto bytes = read_bytes(file("posed.occmap"));
  const double two = 2.0;
  std::memcpy(bytes.data() + bytes.size() - 8 - 12 * 8, &two, 8);  // R(0, 0)
  const std::string error = format_error_loading(file("bad.occmap"), bytes);
  EXPECT_NE(error.find("pose"), std::string::npos) << error;
}

// A binning that is not the library's: saved under its tag, loaded back by the registry.
TEST_F(MapIo, LidarRingsMapRoundTripsWithItsTagAndRings) {
  const SensorPreset preset = test::small_lidar();
  ColumnGrid grid(GridGeometry(preset.geometry));
  insert_points(grid, SensorModel(preset.model), PointSpan::from(test::lidar_scan(grid.geometry())));
  save_map(file("lidar.occmap"), grid, preset.model);
  const std::vector<char> bytes = read_bytes(file("lidar.occmap"));
  std::uint32_t version, tag_length;
  std::memcpy(&version, bytes.data() + 12, 4);
  std::memcpy(&tag_length, bytes.data() + 80, 4);
  EXPECT_EQ(version, 4u);  // version 3 has no code for it
  EXPECT_EQ(std::string(bytes.data() + 84, tag_length), "lidar_rings");
  const LoadedMap loaded = load_map(file("lidar.occmap"));
  const GeometryParams& g = loaded.grid.geometry().params();
  EXPECT_EQ(loaded.grid.geometry().binning(), AngularBinning::lidar_rings);
  EXPECT_EQ(g.row_elevations_rad, preset.geometry.row_elevations_rad);
  EXPECT_TRUE(loaded.grid.geometry() == grid.geometry());
  test::expect_identical(grid, loaded.grid);
  expect_same_maps(grid, loaded.grid, loaded.model);
}

// A map naming a binning this program has not registered is a FormatError naming the tag.
TEST_F(MapIo, UnknownBinningTagIsRefusedNamingIt) {
  const SensorPreset preset = test::small_lidar();
  save_map(file("lidar.occmap"), ColumnGrid(GridGeometry(preset.geometry)), preset.model);
  std::vector<char> bytes = read_bytes(file("lidar.occmap"));
  bytes[84 + 10] = 'z';  // "lidar_rings" -> "lidar_ringz"
  const std::string error = format_error_loading(file("unknown.occmap"), bytes);
  EXPECT_NE(error.find("unknown angular binning 'lidar_ringz'"), std::string::npos) << error;
}

// A binning registered by the program (not built into the library) is saved and loaded by its tag.
class MirroredSphericalBinning : public SphericalBinning {
public:
  using SphericalBinning::SphericalBinning;
  const char* tag() const override { return "test_mirrored"; }
  bool position(double x, double y, double z, double& h, double& v, double& depth) const override {
    return SphericalBinning::position(-x, y, z, h, v, depth);
  }
  Eigen::Vector3d direction_at(double h, double v) const override {
    Eigen::Vector3d d = SphericalBinning::direction_at(h, v);
    d.x() = -d.x();
    return d;
  }
};

TEST_F(MapIo, BinningRegisteredByTheProgramRoundTrips) {
  register_angular_binning("test_mirrored",
                           [](const GeometryParams& p) { return std::make_shared<MirroredSphericalBinning>(p); });
  SensorPreset preset = kinect_v1_paper();
  preset.geometry.angular_binning = "test_mirrored";
  preset.geometry.azimuth_bins = 80;
  preset.geometry.elevation_bins = 60;
  preset.geometry.depth_bins = 128;
  preset.model.sigma_azimuth_rad = preset.model.sigma_elevation_rad = 0.004;
  const ColumnGrid grid = sample_grid(preset, {});
  EXPECT_GT(grid.touched_column_count(), 1000u);
  save_map(file("mirrored.occmap"), grid, preset.model);
  const LoadedMap loaded = load_map(file("mirrored.occmap"));
  EXPECT_EQ(loaded.grid.geometry().binning(), "test_mirrored");
  test::expect_identical(grid, loaded.grid);
  // Mirrored: the scene's box on the left (x < 0) lands in the right half of the columns.
  SensorPreset plain = preset;
  plain.geometry.angular_binning = AngularBinning::spherical;
  const ColumnGrid unmirrored = sample_grid(plain, {});
  const ColumnIndex left = unmirrored.geometry().column(20, 40), right = grid.geometry().column(59, 40);
  EXPECT_EQ(compute_surface(unmirrored).bin[left], compute_surface(grid).bin[right]);
}

// A depth binning registered by the program: version 4, code 2 at offset 60 and its tag after it; loaded
// back by the registry; a tag no binning is registered under is a FormatError naming it.
TEST_F(MapIo, DepthBinningRegisteredByTheProgramRoundTripsWithItsTag) {
  test::register_log_depth_binning();
  SensorPreset preset = kinect_v1_paper();
  preset.geometry.azimuth_bins = 80;
  preset.geometry.elevation_bins = 60;
  preset.geometry.depth_bins = 128;
  preset.geometry.depth_min_m = 0.4;
  preset.geometry.depth_binning = test::LogDepthBinning::kTag;
  preset.model.sigma_azimuth_rad = preset.model.sigma_elevation_rad = 0.004;
  const ColumnGrid grid = sample_grid(preset, {});
  EXPECT_GT(grid.touched_column_count(), 1000u);
  save_map(file("log.occmap"), grid, preset.model);
  std::vector<char> bytes = read_bytes(file("log.occmap"));
  std::uint32_t version, code, tag_length;
  std::memcpy(&version, bytes.data() + 12, 4);
  std::memcpy(&code, bytes.data() + 60, 4);
  std::memcpy(&tag_length, bytes.data() + 64, 4);
  EXPECT_EQ(version, 4u);  // version 3 has no code for it
  EXPECT_EQ(code, 2u);
  ASSERT_EQ(tag_length, 8u);
  EXPECT_EQ(std::string(bytes.data() + 68, tag_length), "test_log");
  double depth_min;
  std::memcpy(&depth_min, bytes.data() + 76, 8);
  EXPECT_EQ(depth_min, 0.4);
  const LoadedMap loaded = load_map(file("log.occmap"));
  EXPECT_EQ(loaded.grid.geometry().params().depth_binning, "test_log");
  EXPECT_EQ(loaded.grid.geometry().params().angular_binning, AngularBinning::spherical);
  EXPECT_TRUE(loaded.grid.geometry() == grid.geometry());
  test::expect_identical(grid, loaded.grid);
  expect_same_maps(grid, loaded.grid, loaded.model);
  bytes[68 + 7] = 'x';  // "test_log" -> "test_lox"
  const std::string error = format_error_loading(file("unknown.occmap"), bytes);
  EXPECT_NE(error.find("unknown depth binning 'test_lox'"), std::string::npos) << error;
}

TEST_F(MapIo, MissingFileOrFolderIsAnIoError) {
  EXPECT_THROW(load_map(file("absent.occmap")), IoError);
  EXPECT_THROW(load_map(folder_.string()), IoError);
}

TEST_F(MapIo, UnwritableTargetIsAnIoErrorAndLeavesNothingBehind) {
  SensorPreset preset = kinect_v1_paper();
  preset.geometry.azimuth_bins = 16;
  preset.geometry.elevation_bins = 16;
  const ColumnGrid grid{GridGeometry(preset.geometry)};
  EXPECT_THROW(save_map(file("no_such_folder/map.occmap"), grid, preset.model), IoError);
  fs::create_directory(file("a_folder"));
  EXPECT_THROW(save_map(file("a_folder"), grid, preset.model), IoError);
  EXPECT_EQ(entries(), std::vector<std::string>{"a_folder"}) << "a failed save must not leave a partial file";
  EXPECT_TRUE(fs::is_empty(file("a_folder")));
}

}  // namespace
}  // namespace occ_improve
