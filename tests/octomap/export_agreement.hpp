#pragma once
// Test helpers shared by tests/octomap/test_export.cpp and tests/pcl/test_map_io_real.cpp: what the
// spherical grid says about a world point, what the export's rule (octomap/export.hpp) makes of a leaf,
// estimated on a lattice of points inside it, and how an OcTree agrees with that. Written from the grid's
// public geometry calls, independently of the exporter's loops.
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/octomap/export.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <Eigen/Geometry>
#include <octomap/OcTree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

namespace occ_improve::test {

enum class Occupancy { unknown = 0, free = 1, occupied = 2 };

/// Log-odds of the spherical voxel holding world point `w`; nullopt where the export counts it unknown
/// (outside the field of view or depth range, never touched, or inside the unknown band).
inline std::optional<float> spherical_log_odds(const ColumnGrid& grid, const Eigen::Isometry3d& world_from_sensor,
                                               const Eigen::Vector3d& w, const OctomapExportOptions& options) {
  const GridGeometry& g = grid.geometry();
  const Eigen::Vector3d p = world_from_sensor.inverse() * w;
  RayPosition r;
  if (!(p.squaredNorm() > 0) || !g.project(p.x(), p.y(), p.z(), r)) return std::nullopt;
  const int bin = g.depth().bin(r.depth);
  if (bin < 0 || bin >= g.depth().bins()) return std::nullopt;
  const float value = grid.log_odds(g.column(r.horizontal_bin, r.vertical_bin), bin);
  if (value == 0.0f || std::abs(value) < logit(0.5 + options.unknown_band_probability)) return std::nullopt;
  return value;
}

inline Occupancy spherical_occupancy(const ColumnGrid& grid, const Eigen::Isometry3d& pose, const Eigen::Vector3d& w,
                                     const OctomapExportOptions& options) {
  const auto l = spherical_log_odds(grid, pose, w, options);
  if (!l) return Occupancy::unknown;
  return *l > 0 ? Occupancy::occupied : Occupancy::free;
}

inline Occupancy octree_occupancy(const octomap::OcTree& tree, const Eigen::Vector3d& w) {
  const octomap::OcTreeNode* node = tree.search(w.x(), w.y(), w.z());
  if (!node) return Occupancy::unknown;
  return tree.isNodeOccupied(node) ? Occupancy::occupied : Occupancy::free;
}

/// FreeLeafRule::crossed's free samples of the finest leaf centred at `centre` (size `size`): the log-odds of
/// the voxel holding its centre when that is free, else the largest of the free voxels holding its 8 corners
/// (a hair inside the leaf, as the export takes them); nullopt when none of them is free.
inline std::optional<float> crossed_free_log_odds(const ColumnGrid& grid, const Eigen::Isometry3d& pose,
                                                  const Eigen::Vector3d& centre, double size,
                                                  const OctomapExportOptions& options) {
  const double half = 0.5 * size * (1.0 - 1e-6);
  std::optional<float> best;
  for (int c = -1; c < 8; ++c) {
    const Eigen::Vector3d w = c < 0 ? centre
                                    : centre + Eigen::Vector3d(c & 1 ? half : -half, c & 2 ? half : -half, c & 4 ? half : -half);
    const auto l = spherical_log_odds(grid, pose, w, options);
    if (c < 0 && l && *l < 0) return l;
    if (l && *l < 0 && (!best || *l > *best)) best = l;
  }
  return best;
}

/// The export's rule for the finest leaf centred at `centre`, estimated on n x n x n points spread over the
/// leaf (its faces included, pulled in by 0.1 %): occupied when any point's voxel is occupied; free, under
/// FreeLeafRule::wholly_free when every point's is free, under crossed when the centre's or a corner's is
/// (crossed_free_log_odds); unknown otherwise. A lattice can miss a feature thinner than its spacing, so the
/// estimate errs only towards free (missed occupied or unknown space) and towards unknown (missed occupied).
/// Under crossed the export also leaves unknown a leaf a carved surface reaches (export.hpp), which the
/// estimate calls free.
struct LeafEstimate {
  Occupancy occupancy = Occupancy::unknown;
  float largest_occupied = -std::numeric_limits<float>::infinity();  ///< largest occupied log-odds seen
};

inline LeafEstimate estimate_leaf(const ColumnGrid& grid, const Eigen::Isometry3d& pose, const Eigen::Vector3d& centre,
                                  double size, const OctomapExportOptions& options, int n) {
  LeafEstimate e;
  bool all_free = true;
  const double half = 0.4995 * size;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d w = centre + Eigen::Vector3d(-half + 2 * half * i / (n - 1), -half + 2 * half * j / (n - 1),
                                                           -half + 2 * half * k / (n - 1));
        const auto l = spherical_log_odds(grid, pose, w, options);
        all_free = all_free && l && *l < 0;
        if (l && *l > 0) e.largest_occupied = std::max(e.largest_occupied, *l);
      }
  const bool free = options.free_leaves == FreeLeafRule::wholly_free
                        ? all_free
                        : crossed_free_log_odds(grid, pose, centre, size, options).has_value();
  e.occupancy = e.largest_occupied > 0 ? Occupancy::occupied : (free ? Occupancy::free : Occupancy::unknown);
  return e;
}

struct Agreement {
  std::size_t compared = 0, agreed = 0;
  std::size_t holes = 0;       ///< leaves the lattice finds occupied space in that are not exported occupied
  std::size_t false_free = 0;  ///< leaves exported free in which the lattice finds non-free space
  std::array<std::size_t, 3> per_class{};  ///< compared leaves per estimated class (unknown, free, occupied)
  double fraction() const { return compared ? static_cast<double>(agreed) / compared : 0.0; }
};

/// The finest leaves holding random points of the grid's frustum (uniform in the binning's angular
/// position, uniform in volume along depth), their exported class against the lattice estimate. The rule
/// forbids holes and false frees outright; other disagreements are thin features the lattice missed.
inline Agreement compare_leaves(const ColumnGrid& grid, const Eigen::Isometry3d& pose, const octomap::OcTree& tree,
                                const OctomapExportOptions& options, int samples, unsigned seed = 7, int lattice = 6) {
  const GridGeometry& g = grid.geometry();
  const GeometryParams& p = g.params();
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> az(g.azimuth().min(), g.azimuth().max()),
      el(g.elevation().min(), g.elevation().max()), cube(std::pow(p.depth_min_m, 3), std::pow(p.depth_max_m, 3));
  Agreement result;
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector3d w = pose * g.point_at(az(random), el(random), std::cbrt(cube(random)));
    const octomap::point3d c = tree.keyToCoord(tree.coordToKey(w.x(), w.y(), w.z()));
    const Eigen::Vector3d centre(c.x(), c.y(), c.z());
    const Occupancy expected = estimate_leaf(grid, pose, centre, tree.getResolution(), options, lattice).occupancy;
    const Occupancy exported = octree_occupancy(tree, centre);
    ++result.compared;
    ++result.per_class[static_cast<std::size_t>(expected)];
    result.agreed += exported == expected ? 1 : 0;
    result.holes += expected == Occupancy::occupied && exported != Occupancy::occupied ? 1 : 0;
    result.false_free += exported == Occupancy::free && expected != Occupancy::free ? 1 : 0;
  }
  return result;
}

}  // namespace occ_improve::test
