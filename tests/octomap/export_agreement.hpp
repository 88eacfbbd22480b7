#pragma once
// Test helpers shared by tests/octomap/test_export.cpp and tests/pcl/test_map_io_real.cpp: what the
// spherical grid says about a world point, what an OcTree says, and their agreement on random samples.
// Written from the grid's public geometry calls, independently of the exporter's loop.
#include "occ_improve/grid.hpp"
#include "occ_improve/octomap/export.hpp"
#include "occ_improve/sensor_model.hpp"

#include <Eigen/Geometry>
#include <octomap/OcTree.h>

#include <array>
#include <cmath>
#include <optional>
#include <random>

namespace occ_improve::test {

enum class Occupancy { unknown = 0, free = 1, occupied = 2 };

/// Log-odds of the spherical voxel holding world point `w`; nullopt where the export leaves it unknown
/// (outside the field of view or depth range, never touched, or inside the unknown band).
inline std::optional<float> spherical_log_odds(const SphericalGrid& grid, const Eigen::Isometry3d& world_from_sensor,
                                               const Eigen::Vector3d& w, const OctomapExportOptions& options) {
  const SphericalGeometry& g = grid.geometry();
  const Eigen::Vector3d p = world_from_sensor.inverse() * w;
  RayPosition r;
  if (!(p.squaredNorm() > 0) || !g.project(p.x(), p.y(), p.z(), r)) return std::nullopt;
  const int bin = g.depth().bin(r.depth);
  if (bin < 0 || bin >= g.depth().bins()) return std::nullopt;
  const float value = grid.log_odds(g.column(r.horizontal_bin, r.vertical_bin), bin);
  if (std::abs(value) < logit(0.5 + options.unknown_band_probability)) return std::nullopt;
  return value;
}

inline Occupancy spherical_occupancy(const SphericalGrid& grid, const Eigen::Isometry3d& pose, const Eigen::Vector3d& w,
                                     const OctomapExportOptions& options) {
  const auto l = spherical_log_odds(grid, pose, w, options);
  if (!l) return Occupancy::unknown;
  return *l >= static_cast<float>(logit(options.occupancy_threshold)) ? Occupancy::occupied : Occupancy::free;
}

inline Occupancy octree_occupancy(const octomap::OcTree& tree, const Eigen::Vector3d& w) {
  const octomap::OcTreeNode* node = tree.search(w.x(), w.y(), w.z());
  if (!node) return Occupancy::unknown;
  return tree.isNodeOccupied(node) ? Occupancy::occupied : Occupancy::free;
}

struct Agreement {
  std::size_t compared = 0, agreed = 0, near_boundary = 0;
  std::array<std::size_t, 3> per_class{};  ///< compared samples per spherical class (unknown, free, occupied)
  double fraction() const { return compared ? static_cast<double>(agreed) / compared : 0.0; }
};

/// Random points in the grid's frustum (uniform in the binning's angular position, uniform in volume
/// along depth), for either binning. A sample counts
/// only when its OcTree leaf lies "away from boundaries": the leaf's centre and its 8 corners (pulled in
/// by 0.1 %) all fall in spherical voxels of the same class.
inline Agreement compare_occupancy(const SphericalGrid& grid, const Eigen::Isometry3d& pose, const octomap::OcTree& tree,
                                   const OctomapExportOptions& options, int samples, unsigned seed = 7) {
  const SphericalGeometry& g = grid.geometry();
  const GeometryParams& p = g.params();
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> az(g.azimuth().min(), g.azimuth().max()),
      el(g.elevation().min(), g.elevation().max()), cube(std::pow(p.depth_min_m, 3), std::pow(p.depth_max_m, 3));
  const double half = 0.4995 * tree.getResolution();
  Agreement result;
  for (int i = 0; i < samples; ++i) {
    const double h = az(random), v = el(random);
    const Eigen::Vector3d w = pose * g.point_at(h, v, std::cbrt(cube(random)));
    const octomap::point3d c = tree.keyToCoord(tree.coordToKey(w.x(), w.y(), w.z()));
    const Eigen::Vector3d centre(c.x(), c.y(), c.z());
    const Occupancy expected = spherical_occupancy(grid, pose, centre, options);
    bool uniform = true;
    for (int corner = 0; corner < 8 && uniform; ++corner) {
      const Eigen::Vector3d offset((corner & 1) ? half : -half, (corner & 2) ? half : -half, (corner & 4) ? half : -half);
      uniform = spherical_occupancy(grid, pose, centre + offset, options) == expected;
    }
    if (!uniform) {
      ++result.near_boundary;
      continue;
    }
    ++result.compared;
    ++result.per_class[static_cast<std::size_t>(expected)];
    result.agreed += octree_occupancy(tree, w) == expected ? 1 : 0;
  }
  return result;
}

}  // namespace occ_improve::test
