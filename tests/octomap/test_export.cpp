// Export of the spherical grid to OctoMap (octomap/export.hpp): leaves follow the conversion rule (no
// occupied space missed, nothing but free space written free) in the tree and in files read back with
// OctoMap, a thin wall exports without holes, maps from two poses merge by the documented rule, writing
// leaves the caller's tree alone, and bad input is refused with typed errors and no half-written file.
#include "support/temp_folder.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/octomap/export.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"
#include "octomap/export_agreement.hpp"
#include "support/lidar_scene.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;
using test::Occupancy;

constexpr double kResolution = 0.03;
// Share of sampled leaves whose exported class equals the lattice estimate (the rest: thin features the
// lattice misses). Measured: see the printed figures.
constexpr double kMinAgreement = 0.97;

// The sample frame in the paper preset (clamped) and in an exact-mode grid, built once.
const ColumnGrid& sample_grid(UpdateMode mode) {
  auto build = [](UpdateMode m) {
    const SensorPreset preset = kinect_v1_paper();
    GridOptions options;
    options.mode = m;
    auto grid = std::make_unique<ColumnGrid>(GridGeometry(preset.geometry), options);
    const auto points = sample::generate_scene().points();
    insert_points(*grid, SensorModel(preset.model), PointSpan::from(points));
    return grid;
  };
  if (mode == UpdateMode::clamped) {
    static const auto clamped = build(UpdateMode::clamped);
    return *clamped;
  }
  static const auto exact = build(UpdateMode::exact);
  return *exact;
}

Eigen::Isometry3d some_pose() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(1.0, -2.0, 0.5));
  pose.rotate(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1.0, -0.2).normalized()));
  return pose;
}

// A finest-level leaf centre inside a (possibly pruned) leaf: its lowest corner leaf. Pruning merges 8
// children only when all exist with one value, so every finest leaf inside was written with that value.
Eigen::Vector3d finest_centre(const octomap::OcTree::leaf_iterator& it, double resolution) {
  const double inset = 0.5 * (it.getSize() - resolution);
  return Eigen::Vector3d(it.getX() - inset, it.getY() - inset, it.getZ() - inset);
}

using OctomapExport = test::TempFolderTest;

// The rule's two guarantees hold on every compared leaf; the lattice estimate agrees otherwise except
// where it misses a feature thinner than its spacing.
void expect_agreement(const test::Agreement& a, double min_fraction) {
  EXPECT_EQ(a.compared, a.per_class[0] + a.per_class[1] + a.per_class[2]);
  EXPECT_GT(a.per_class[static_cast<int>(Occupancy::free)], 500u);
  EXPECT_GT(a.per_class[static_cast<int>(Occupancy::occupied)], 20u);
  EXPECT_GT(a.per_class[static_cast<int>(Occupancy::unknown)], 100u);
  EXPECT_EQ(a.holes, 0u) << "leaves holding occupied space exported as not occupied";
  EXPECT_EQ(a.false_free, 0u) << "leaves holding non-free space exported free";
  const std::string figures = std::to_string(a.agreed) + "/" + std::to_string(a.compared) + " (occupied " +
                              std::to_string(a.per_class[2]) + ", free " + std::to_string(a.per_class[1]) +
                              ", unknown " + std::to_string(a.per_class[0]) + ")";
  std::printf("agreement with the lattice estimate: %s\n", figures.c_str());
  ::testing::Test::RecordProperty("agreement", figures);
  EXPECT_GE(a.fraction(), min_fraction) << figures;
}

// The grid exported from some_pose(), with the report's counts checked.
std::unique_ptr<octomap::OcTree> exported(const ColumnGrid& grid, const OctomapExportOptions& options) {
  OctomapExportReport report;
  auto tree = to_octree(grid, some_pose(), kResolution, options, &report);
  EXPECT_GT(report.free_written, 100000u);
  EXPECT_GT(report.occupied_written, 1000u);
  return tree;
}

TEST_F(OctomapExport, FilesReadBackAgreeWithTheGrid) {
  const ColumnGrid& grid = sample_grid(UpdateMode::clamped);
  const Eigen::Isometry3d pose = some_pose();
  const OctomapExportOptions options;
  const auto tree = exported(grid, options);
  // OctoMap keeps its thresholds as float log-odds: equal to float precision.
  EXPECT_NEAR(tree->getClampingThresMin(), grid.options().probability_min, 1e-7);
  EXPECT_NEAR(tree->getClampingThresMax(), grid.options().probability_max, 1e-7);

  expect_agreement(test::compare_leaves(grid, pose, *tree, options, 5000), kMinAgreement);

  write_octree(*tree, file("map.ot"));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(file("map.ot")));
  auto* full = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(full, nullptr);
  expect_agreement(test::compare_leaves(grid, pose, *full, options, 5000, 11), kMinAgreement);

  write_octree(*tree, file("map.bt"));
  const octomap::OcTree binary(file("map.bt"));
  ASSERT_GT(binary.size(), 0u);
  expect_agreement(test::compare_leaves(grid, pose, binary, options, 5000, 13), kMinAgreement);
  EXPECT_EQ(entry_count(), 2u) << "no temporary file may be left behind";
}

TEST_F(OctomapExport, PixelNativeGridAgreesToo) {
  const SensorPreset preset = kinect_v1(sample::generate_scene().intrinsics);
  ColumnGrid grid(GridGeometry(preset.geometry));
  insert_points(grid, SensorModel(preset.model), PointSpan::from(sample::generate_scene().points()));
  for (FreeLeafRule rule : {FreeLeafRule::crossed, FreeLeafRule::wholly_free}) {
    OctomapExportOptions options;
    options.free_leaves = rule;
    expect_agreement(test::compare_leaves(grid, some_pose(), *exported(grid, options), options, 5000), kMinAgreement);
  }
}

// Finest-level leaves of each class in `tree` (pruned leaves expanded), each passed to visit(key, class).
template <typename Visit>
void for_each_finest_leaf(const octomap::OcTree& tree, Visit&& visit) {
  const unsigned max_depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const unsigned span = 1u << (max_depth - it.getDepth());
    const octomap::OcTreeKey k0 = it.getIndexKey();
    const Occupancy c = tree.isNodeOccupied(*it) ? Occupancy::occupied : Occupancy::free;
    for (unsigned x = 0; x < span; ++x)
      for (unsigned y = 0; y < span; ++y)
        for (unsigned z = 0; z < span; ++z)
          visit(octomap::OcTreeKey(static_cast<octomap::key_type>(k0[0] + x), static_cast<octomap::key_type>(k0[1] + y),
                                   static_cast<octomap::key_type>(k0[2] + z)),
                c);
  }
}

Occupancy class_at(const octomap::OcTree& tree, const octomap::OcTreeKey& key) {
  const octomap::OcTreeNode* node = tree.search(key);
  return !node ? Occupancy::unknown : tree.isNodeOccupied(node) ? Occupancy::occupied : Occupancy::free;
}

// The two free rules on one grid of two fused views (the second 5 cm to the side, so that returns are carved
// at depth edges): crossed writes free every finest leaf wholly_free does (a review found 26 such leaves left
// unknown when a carved return's mark blocked leaves no boundary reaches), and more (the leaves a free-space
// boundary passes whose centre or a corner is free); the occupied leaves are the same.
TEST_F(OctomapExport, CrossedWritesFreeWhatWhollyFreeDoesAndTheLeavesFreeSpaceCrosses) {
  const SensorPreset preset = kinect_v1_paper();
  ColumnGrid grid(GridGeometry(preset.geometry));
  auto points = sample::generate_scene().points();
  insert_points(grid, SensorModel(preset.model), PointSpan::from(points));
  for (auto& p : points) p.x() += 0.05f;
  insert_points(grid, SensorModel(preset.model), PointSpan::from(points));
  for (const double resolution : {0.05, 0.1}) {
    OctomapExportOptions wholly;
    wholly.free_leaves = FreeLeafRule::wholly_free;
    const auto crossed_tree = to_octree(grid, some_pose(), resolution, {});
    const auto wholly_tree = to_octree(grid, some_pose(), resolution, wholly);
    std::size_t wholly_free = 0, crossed_free = 0, lost = 0, occupied_differ = 0;
    for_each_finest_leaf(*wholly_tree, [&](const octomap::OcTreeKey& key, Occupancy c) {
      const Occupancy other = class_at(*crossed_tree, key);
      if (c == Occupancy::occupied) {
        occupied_differ += other == Occupancy::occupied ? 0 : 1;
      } else {
        ++wholly_free;
        lost += other == Occupancy::free ? 0 : 1;
      }
    });
    for_each_finest_leaf(*crossed_tree, [&](const octomap::OcTreeKey& key, Occupancy c) {
      crossed_free += c == Occupancy::free ? 1 : 0;
      occupied_differ += c == Occupancy::occupied && class_at(*wholly_tree, key) != Occupancy::occupied ? 1 : 0;
    });
    std::printf("%.0f cm finest leaves written free: crossed %zu, wholly_free %zu\n", resolution * 100, crossed_free,
                wholly_free);
    EXPECT_EQ(lost, 0u) << resolution;
    EXPECT_EQ(occupied_differ, 0u) << resolution;
    EXPECT_GT(crossed_free, wholly_free + wholly_free / 10) << resolution;
  }
}

// A spinning LiDAR's range image (lidar_rings: uneven rings, range along each ring's ray). The rule's
// guarantees (no holes, no false free) hold on every leaf; the share agreeing with the lattice estimate
// was 0.963 when measured (camera grids: > 0.97): the columns are 5-20 times wider than a camera's, so
// more leaves straddle a column or depth-bin boundary where the 6^3 lattice and the export differ.
constexpr double kMinLidarAgreement = 0.95;

TEST_F(OctomapExport, LidarRingsGridAgreesToo) {
  const SensorPreset preset = test::small_lidar();
  ColumnGrid grid(GridGeometry(preset.geometry));
  insert_points(grid, SensorModel(preset.model), PointSpan::from(test::lidar_scan(grid.geometry())));
  const OctomapExportOptions options;
  const auto tree = exported(grid, options);
  ASSERT_GT(tree->size(), 0u);
  expect_agreement(test::compare_leaves(grid, some_pose(), *tree, options, 5000), kMinLidarAgreement);
}

// A 64 x 48 camera facing a wall 2 m away, one point per pixel 1 cm apart: the kinect_v1 preset's occupied
// shell there is a few millimetres deep, thinner than a 2 cm leaf. Leaf centres fell between its depth
// bins and the export held no occupied leaf at all; every leaf holding a wall point must be occupied.
TEST_F(OctomapExport, AThinWallExportsWithoutHoles) {
  const PinholeIntrinsics camera{200.0, 200.0, 32.0, 24.0, 64, 48};
  std::vector<Eigen::Vector3f> wall;
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) wall.emplace_back((u - 32) * 0.01f, (v - 24) * 0.01f, 2.0f);
  const SensorPreset preset = kinect_v1(camera);
  ColumnGrid grid(GridGeometry(preset.geometry));
  insert_points(grid, SensorModel(preset.model), PointSpan::from(wall));
  for (double resolution : {0.01, 0.02, 0.05}) {
    OctomapExportReport report;
    const auto tree = to_octree(grid, Eigen::Isometry3d::Identity(), resolution, {}, &report);
    std::set<octomap::OcTreeKey, bool (*)(const octomap::OcTreeKey&, const octomap::OcTreeKey&)> wall_leaves(
        [](const octomap::OcTreeKey& a, const octomap::OcTreeKey& b) {
          return std::lexicographical_compare(&a.k[0], &a.k[3], &b.k[0], &b.k[3]);
        });
    std::size_t holes = 0;
    for (const Eigen::Vector3f& p : wall) {
      const octomap::OcTreeKey key = tree->coordToKey(p.x(), p.y(), p.z());
      if (!wall_leaves.insert(key).second) continue;
      const octomap::OcTreeNode* node = tree->search(key);
      holes += node && tree->isNodeOccupied(node) ? 0 : 1;
    }
    EXPECT_EQ(holes, 0u) << "of " << wall_leaves.size() << " leaves holding wall points at " << resolution << " m";
    // Occupied leaves lie on the wall: within a leaf and the shell's depth (sigma_z = 5.7 mm at 2 m) of it.
    std::size_t occupied = 0;
    for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
      if (!tree->isNodeOccupied(*it)) continue;
      occupied += 1;
      EXPECT_NEAR(it.getZ(), 2.0, resolution + 0.02) << "occupied leaf off the wall at " << resolution << " m";
    }
    EXPECT_GE(occupied, wall_leaves.size());
    EXPECT_EQ(report.occupied_written, occupied);
    EXPECT_GT(report.free_written, 0u);
  }
}

// Free leaves carry the log-odds of the voxel at their centre, or where that is not free the largest of their
// free corners' (FreeLeafRule::crossed);
// occupied ones the largest of the occupied voxels reaching them, so at least the largest a lattice inside
// them finds.
TEST_F(OctomapExport, LogOddsAreCarriedOverAndExactModeIsNotClampedAtTheGridsBounds) {
  for (UpdateMode mode : {UpdateMode::clamped, UpdateMode::exact}) {
    const ColumnGrid& grid = sample_grid(mode);
    const Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    const OctomapExportOptions options;
    const auto tree = to_octree(grid, pose, kResolution, options);
    std::size_t free_checked = 0, free_equal = 0, occupied_checked = 0, occupied_below = 0, leaf = 0;
    float lowest = 0;
    for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
      lowest = std::min(lowest, it->getLogOdds());
      if (++leaf % 7 != 0) continue;  // every 7th leaf keeps the test short
      const Eigen::Vector3d centre = finest_centre(it, kResolution);
      if (it->getLogOdds() < 0) {  // crossed (the default): the centre's, else the largest free corner's
        const auto expected = test::crossed_free_log_odds(grid, pose, centre, kResolution, options);
        ++free_checked;
        free_equal += expected && std::abs(*expected - it->getLogOdds()) <= 1e-6f ? 1 : 0;
      } else {
        const test::LeafEstimate e = test::estimate_leaf(grid, pose, centre, kResolution, options, 4);
        ++occupied_checked;
        occupied_below += it->getLogOdds() < e.largest_occupied ? 1 : 0;
      }
    }
    const int m = static_cast<int>(mode);
    EXPECT_GT(free_checked, 1000u) << "mode " << m;
    EXPECT_EQ(free_equal, free_checked) << "mode " << m;
    EXPECT_GT(occupied_checked, 100u) << "mode " << m;
    EXPECT_EQ(occupied_below, 0u) << "of " << occupied_checked << " occupied leaves, mode " << m;
    if (mode == UpdateMode::exact) {
      EXPECT_LT(lowest, grid.log_odds_min() - 10.0f) << "exact-mode free space must keep its large log-odds";
    } else {
      EXPECT_EQ(lowest, grid.log_odds_min());
    }
  }
}

// The merged tree against the two views exported alone: every leaf is the clamped sum of theirs.
TEST_F(OctomapExport, TwoPosesMergeByAddingLogOddsThenClamping) {
  const ColumnGrid& grid = sample_grid(UpdateMode::clamped);
  const Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
  b.translate(Eigen::Vector3d(0.4, 0.0, 0.6));
  b.rotate(Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitY()));
  const OctomapExportOptions options;
  auto tree = to_octree(grid, a, kResolution, options);
  add_to_octree(*tree, grid, b, options);
  const auto alone_a = to_octree(grid, a, kResolution, options), alone_b = to_octree(grid, b, kResolution, options);
  const float lo = grid.log_odds_min(), hi = grid.log_odds_max();

  std::size_t both = 0, checked = 0, matching = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    const Eigen::Vector3d w = finest_centre(it, kResolution);
    const octomap::OcTreeNode* na = alone_a->search(w.x(), w.y(), w.z());
    const octomap::OcTreeNode* nb = alone_b->search(w.x(), w.y(), w.z());
    ASSERT_TRUE(na || nb) << "a leaf neither view wrote";
    const float la = na ? na->getLogOdds() : 0.0f, lb = nb ? nb->getLogOdds() : 0.0f;
    const float expected = std::clamp(la + lb, lo, hi);
    both += (na && nb) ? 1 : 0;
    ++checked;
    matching += std::abs(expected - it->getLogOdds()) <= 1e-5f ? 1 : 0;
  }
  EXPECT_GT(both, 10000u) << "the two views must overlap for the test to mean something";
  EXPECT_EQ(matching, checked);
}

// A digest of every leaf (key and log-odds) and of the node count, to see any change to the tree.
std::pair<std::size_t, double> digest(const octomap::OcTree& tree) {
  double sum = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k = it.getKey();
    sum += it->getLogOdds() * (1.0 + k[0] * 1e-5 + k[1] * 1e-7 + k[2] * 1e-9 + it.getDepth() * 1e-3);
  }
  return {tree.size(), sum};
}

TEST_F(OctomapExport, WritingLeavesTheCallersTreeUnchanged) {
  const auto tree = to_octree(sample_grid(UpdateMode::clamped), Eigen::Isometry3d::Identity(), 0.05);
  const auto before = digest(*tree);
  write_octree(*tree, file("a.bt"));
  EXPECT_EQ(digest(*tree), before) << ".bt writing pruned or thresholded the caller's tree";
  write_octree(*tree, file("a.ot"));
  EXPECT_EQ(digest(*tree), before);
  // The same tree written with OctoMap's own pruning writer does change (what this test guards against).
  octomap::OcTree copy(*tree);
  copy.writeBinary(file("pruned.bt"));
  EXPECT_NE(digest(copy), before);
}

// Writes lazily (no inner update, no pruning) a block of leaves whose values come in runs, so that whole
// octants are equal and prune, some mixed ones do not, and a few leaves sit in octants pruned before.
void write_lazily(octomap::OcTree& tree, unsigned seed, unsigned side = 128) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> value(0, 7);
  const auto base = static_cast<octomap::key_type>(32768 - side / 2);
  for (unsigned x = 0; x < side; ++x)
    for (unsigned y = 0; y < side; ++y)
      for (unsigned z = 0; z < 16; ++z) {
        const bool uniform_octant = ((x / 8 + y / 8 + z / 8 + seed) % 3) != 0;
        const float log_odds = uniform_octant ? -2.0f + static_cast<float>((x / 8 + seed) % 2) : 0.5f * value(random);
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(base + x), static_cast<octomap::key_type>(base + y),
                                     static_cast<octomap::key_type>(base + z));
        tree.updateNode(key, log_odds, true);
      }
}

void expect_same_trees(const octomap::OcTree& ours, const octomap::OcTree& octomaps, const char* round) {
  EXPECT_TRUE(ours == octomaps) << round;
  std::ostringstream a, b;
  ASSERT_TRUE(ours.writeData(a).good() && octomaps.writeData(b).good());
  EXPECT_TRUE(a.str() == b.str()) << round << ": " << a.str().size() << " bytes against " << b.str().size();
  EXPECT_EQ(ours.size(), octomaps.size()) << round;
}

// update_inner_occupancy_and_prune is OctoMap's updateInnerOccupancy() + prune(), node for node: fresh
// lazily written trees, and trees pruned before and written again (prune stops at the first level that
// prunes nothing), written to the same bytes.
TEST_F(OctomapExport, InnerUpdateAndPruningAreOctomapsOwn) {
  octomap::OcTree ours(0.05), octomaps(0.05);
  for (const unsigned round : {1u, 2u, 3u}) {
    write_lazily(ours, round);
    write_lazily(octomaps, round);
    const std::size_t before = octomaps.size();
    update_inner_occupancy_and_prune(ours);
    octomaps.updateInnerOccupancy();
    octomaps.prune();
    // updateNode adds log-odds: later rounds move values, so fewer octants stay equal than in the first.
    EXPECT_LT(octomaps.size(), round == 1 ? before / 2 : before) << "round " << round << ": nothing pruned";
    expect_same_trees(ours, octomaps, round == 1 ? "fresh tree" : "tree pruned before");
  }
  // The export itself: its tree, finished again by OctoMap, is unchanged (already updated and pruned).
  const auto exported = to_octree(sample_grid(UpdateMode::clamped), Eigen::Isometry3d::Identity(), 0.05);
  octomap::OcTree again(*exported);
  again.updateInnerOccupancy();
  again.prune();
  expect_same_trees(*exported, again, "export");
}

// A stop request is obeyed inside the pass (OctoMap's own calls poll nothing).
TEST_F(OctomapExport, InnerUpdateAndPruningObeyAStopRequest) {
  octomap::OcTree tree(0.05);
  write_lazily(tree, 1, 512);  // 4 M leaves: the inner update alone visits more nodes than a poll's 65 536
  ASSERT_GT(tree.size() - tree.getNumLeafNodes(), 65536u * 2);
  struct Withdrawn {
    ~Withdrawn() { clear_stop_request(); }  // whatever the test's outcome, for the tests after it
  } withdrawn;
  request_stop(SIGINT);
  EXPECT_THROW(update_inner_occupancy_and_prune(tree), Cancelled);
  clear_stop_request();
  update_inner_occupancy_and_prune(tree);  // the same tree finishes once the request is withdrawn
  EXPECT_GT(tree.getNumLeafNodes(), 0u);
}

// write_octree writes the headers itself (OctoMap's writer prints " done." to stderr): OctoMap's own bytes
// but for the line that says occ_improve wrote the file, which OctoMap's readers skip.
// .ot: the bytes of OctoMap's write(); .bt: those of its writeBinary() (maximum likelihood, pruned: a held-out
// trial's .bt held 1.14 M nodes, 368 kB, where OctoMap's own writer gives 0.61 M, 237 kB), without the caller's
// tree changing; both with our line after OctoMap's first.
TEST_F(OctomapExport, TreeFilesHoldOctomapsOwnBytesAndSayWhoWroteThem) {
  const auto tree = to_octree(sample_grid(UpdateMode::clamped), Eigen::Isometry3d::Identity(), 0.05);
  const std::size_t nodes = tree->size();
  for (const bool full : {false, true}) {
    const std::string path = file(full ? "a.ot" : "a.bt");
    write_octree(*tree, path);
    EXPECT_EQ(tree->size(), nodes) << "the caller's tree changed";
    std::ostringstream expected;
    octomap::OcTree copy(*tree);
    ASSERT_TRUE(full ? tree->write(expected) : copy.writeBinary(expected));
    if (!full) {
      EXPECT_LT(copy.size(), nodes * 3 / 4) << "maximum likelihood merges more than equal log-odds do";
    }
    std::string octomaps = expected.str();
    octomaps.insert(octomaps.find('\n') + 1, "# written by occ_improve\n");
    std::ifstream in(path, std::ios::binary);
    const std::string written{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    EXPECT_GT(written.size(), 1000u);
    EXPECT_TRUE(written == octomaps) << path << ": " << written.size() << " bytes against " << octomaps.size();
    EXPECT_TRUE(is_octomap_file(path));
    if (full) {
      std::unique_ptr<octomap::AbstractOcTree> back(octomap::AbstractOcTree::read(path));
      ASSERT_NE(back, nullptr) << path;
      EXPECT_EQ(back->size(), tree->size()) << path;
    } else {
      EXPECT_EQ(octomap::OcTree(path).size(), copy.size()) << path;
    }
  }
  ASSERT_TRUE(tree->writeBinary(file("octomaps.bt")));  // a tree another program wrote
  EXPECT_FALSE(is_octomap_file(file("octomaps.bt")));
}

// The .bt bytes against writeBinary() on trees built to reach its corners: prune() stops at the first level
// where nothing merges, so children one level up that would merge are kept (a tree whose deepest inner level
// has no merge and the level above one); an occupancy threshold above the clamping maximum (every leaf
// free once thresholded); a random tree; an empty one.
TEST_F(OctomapExport, BinaryFilesAreWriteBinarysOnTreesAtItsCorners) {
  std::vector<std::pair<std::string, octomap::OcTree>> trees;
  {
    octomap::OcTree t(0.01);
    const octomap::OcTreeKey base(32768, 32768, 32768);
    // A node two levels up whose 8 children each hold 8 leaves of one free value, a different one per child:
    // pruned already by equal values, so the deepest level has nothing left to merge.
    for (unsigned c = 0; c < 8; ++c)
      for (unsigned k = 0; k < 8; ++k)
        t.setNodeValue(octomap::OcTreeKey(static_cast<octomap::key_type>(base[0] + 2 * (c & 1) + (k & 1)),
                                          static_cast<octomap::key_type>(base[1] + (c & 2) + ((k >> 1) & 1)),
                                          static_cast<octomap::key_type>(base[2] + (c & 4) / 2 + ((k >> 2) & 1))),
                       -1.0f - 0.1f * static_cast<float>(c), true);
    t.updateInnerOccupancy();
    t.prune();
    trees.emplace_back("prune's stop", t);
  }
  std::mt19937 random(2);
  for (const double threshold : {0.5, 0.99}) {
    octomap::OcTree t(0.01);
    t.setOccupancyThres(threshold);
    std::uniform_real_distribution<float> log_odds(-2.0f, 0.3f);
    for (int i = 0; i < 20000; ++i)
      t.setNodeValue(octomap::OcTreeKey(static_cast<octomap::key_type>(32768 + random() % 32),
                                        static_cast<octomap::key_type>(32768 + random() % 32),
                                        static_cast<octomap::key_type>(32768 + random() % 32)),
                     log_odds(random), true);
    t.updateInnerOccupancy();
    t.prune();
    trees.emplace_back("random, occupancy threshold " + std::to_string(threshold), t);
  }
  trees.emplace_back("empty", octomap::OcTree(0.1));
  for (auto& [name, tree] : trees) {
    write_octree(tree, file("t.bt"));
    std::ostringstream expected;
    octomap::OcTree copy(tree);
    ASSERT_TRUE(copy.writeBinary(expected)) << name;
    std::string octomaps = expected.str();
    octomaps.insert(octomaps.find('\n') + 1, "# written by occ_improve\n");
    std::ifstream in(file("t.bt"), std::ios::binary);
    const std::string written{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    EXPECT_TRUE(written == octomaps) << name << ": " << written.size() << " bytes against " << octomaps.size();
  }
}

TEST_F(OctomapExport, BadResolutionPoseAndPathsAreRefused) {
  const ColumnGrid& grid = sample_grid(UpdateMode::clamped);
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  EXPECT_THROW(to_octree(grid, identity, 0.0), InvalidParameter);
  EXPECT_THROW(to_octree(grid, identity, -0.02), InvalidParameter);
  EXPECT_THROW(to_octree(grid, identity, 1e-4), ResourceLimit);

  auto tree = make_octree(grid, 0.05);
  Eigen::Isometry3d scaled = identity;
  scaled.linear() *= 2.0;
  EXPECT_THROW(add_to_octree(*tree, grid, scaled), InvalidParameter);
  Eigen::Isometry3d reflected = identity;
  reflected.linear()(0, 0) = -1.0;
  EXPECT_THROW(add_to_octree(*tree, grid, reflected), InvalidParameter);
  // A rotation written with 4 decimals (7-Scenes' pose files: |R^T R - I| = 1.5e-4, refused before) is taken
  // as the nearest rotation, as the tools read pose files.
  Eigen::Isometry3d exact = identity;
  exact.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::Isometry3d rounded = exact;
  rounded.linear() = (exact.linear() * 1e4).array().round().matrix() / 1e4;
  ASSERT_GT((rounded.linear().transpose() * rounded.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-5);
  OctomapExportReport from_exact, from_rounded;
  to_octree(grid, exact, 0.05, {}, &from_exact);
  EXPECT_NO_THROW(to_octree(grid, rounded, 0.05, {}, &from_rounded));
  EXPECT_NEAR(static_cast<double>(from_rounded.occupied_written), static_cast<double>(from_exact.occupied_written),
              0.01 * static_cast<double>(from_exact.occupied_written));
  Eigen::Isometry3d not_finite = identity;
  not_finite.translation().x() = std::nan("");
  EXPECT_THROW(add_to_octree(*tree, grid, not_finite), InvalidParameter);
  Eigen::Isometry3d far_away = identity;
  far_away.translation() = Eigen::Vector3d(1e4, 0, 0);
  EXPECT_THROW(add_to_octree(*tree, grid, far_away), InvalidParameter);
  EXPECT_EQ(tree->size(), 0u) << "a refused export must not touch the tree";

  add_to_octree(*tree, grid, identity);
  EXPECT_THROW(write_octree(*tree, file("no_such_folder/map.bt")), IoError);
  fs::create_directory(file("taken.ot"));
  EXPECT_THROW(write_octree(*tree, file("taken.ot")), IoError);
  EXPECT_THROW(write_octree(*tree, file("map.pcd")), InvalidParameter);
  EXPECT_EQ(entry_count(), 1u) << "only the folder standing in the way may remain";
}

}  // namespace
}  // namespace occ_improve
