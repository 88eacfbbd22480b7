#include "occ_improve/octomap/export.hpp"

#include "occ_improve/atomic_file.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/sensor_model.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace occ_improve {
namespace {

using detail::require_parameter;

// Memory of one OcTree leaf: the node (float + children pointer, 16 bytes) plus its share of the parent's
// 8-pointer child array (8 bytes), plus ~1/7 for the inner levels above. Used only for the cap estimate.
constexpr double kBytesPerLeaf = 28.0;

void require_rigid(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d& m = pose.matrix();
  if (!m.allFinite()) throw InvalidParameter("pose (world <- sensor) has non-finite entries");
  if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
    throw InvalidParameter("pose (world <- sensor) is not an affine transform: last row must be 0 0 0 1");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const double orthogonality = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality > 1e-6 || std::abs(r.determinant() - 1.0) > 1e-6) {
    std::ostringstream msg;
    msg << "pose (world <- sensor) is not a rigid transform: |R^T R - I| = " << orthogonality
        << ", det R = " << r.determinant() << " (scaling, shear or reflection)";
    throw InvalidParameter(msg.str());
  }
}

// The far end of everything the grid knows: beyond the last touched bin of every column all voxels are
// unknown, so the export need not visit them (a table-top frame in an 8 m grid ends near 2 m).
double known_far_m(const SphericalGrid& grid) {
  const SphericalGeometry& g = grid.geometry();
  int last_bin = -1;
  for (std::size_t c = 0; c < g.column_count(); ++c) {
    const ColumnData* column = grid.find(static_cast<ColumnIndex>(c));
    if (column) last_bin = std::max(last_bin, column->window_end() - 1);
  }
  return last_bin < 0 ? g.depth().min() : g.depth().upper(last_bin);
}

// The field of view's boundary sampled on a lattice of kSamples x kSamples angular positions (the axes'
// extents, in the binning's unit), for any binning.
constexpr int kSamples = 17;
template <typename Visit>
void for_each_lattice_position(const SphericalGeometry& g, Visit&& visit) {
  const UniformAxis &h = g.azimuth(), &v = g.elevation();
  for (int i = 0; i < kSamples; ++i)
    for (int j = 0; j < kSamples; ++j)
      visit(i, j, h.min() + i * (h.max() - h.min()) / (kSamples - 1), v.min() + j * (v.max() - v.min()) / (kSamples - 1));
}

// Volume of the field of view out to depth coordinate far_m: per lattice cell, its solid angle (the
// parallelogram of two edge directions) x (r_far^3 - r_near^3) / 3 at the cell's first corner. An
// estimate for the memory cap only.
double frustum_volume_m3(const SphericalGeometry& g, double far_m) {
  std::vector<Eigen::Vector3d> d(kSamples * kSamples);
  std::vector<double> far_range(d.size());
  for_each_lattice_position(g, [&](int i, int j, double h, double v) {
    d[static_cast<std::size_t>(i * kSamples + j)] = g.direction_at(h, v);
    far_range[static_cast<std::size_t>(i * kSamples + j)] = g.point_at(h, v, far_m).norm();
  });
  const double near_m = g.depth().min();
  double volume = 0;
  for (int i = 0; i + 1 < kSamples; ++i)
    for (int j = 0; j + 1 < kSamples; ++j) {
      const auto at = [&](int a, int b) { return static_cast<std::size_t>(a * kSamples + b); };
      const double solid_angle = (d[at(i + 1, j)] - d[at(i, j)]).cross(d[at(i, j + 1)] - d[at(i, j)]).norm();
      volume += solid_angle * std::max(0.0, std::pow(far_range[at(i, j)], 3) - std::pow(near_m, 3)) / 3.0;
    }
  return volume;
}

// World-frame bounding box of the field of view out to far_m: the lattice at the near and far depths
// (and the sensor origin), padded by the far cap's bulge between lattice directions.
void frustum_bounds(const SphericalGeometry& g, double far_m, const Eigen::Isometry3d& pose, Eigen::Vector3d& lo,
                    Eigen::Vector3d& hi) {
  lo = hi = pose.translation();
  double widest_step_rad = 0, far_range = 0;
  for_each_lattice_position(g, [&](int i, int j, double h, double v) {
    for (double depth : {g.depth().min(), far_m}) {
      const Eigen::Vector3d p = g.point_at(h, v, depth);
      far_range = std::max(far_range, p.norm());
      const Eigen::Vector3d w = pose * p;
      lo = lo.cwiseMin(w);
      hi = hi.cwiseMax(w);
    }
    const Eigen::Vector3d d = g.direction_at(h, v);
    if (i + 1 < kSamples) {
      const double next_h = h + (g.azimuth().max() - g.azimuth().min()) / (kSamples - 1);
      widest_step_rad = std::max(widest_step_rad, std::acos(std::min(1.0, d.dot(g.direction_at(next_h, v)))));
    }
    if (j + 1 < kSamples) {
      const double next_v = v + (g.elevation().max() - g.elevation().min()) / (kSamples - 1);
      widest_step_rad = std::max(widest_step_rad, std::acos(std::min(1.0, d.dot(g.direction_at(h, next_v)))));
    }
  });
  const double bulge = far_range * (1.0 - std::cos(widest_step_rad)) + 1e-6;
  lo.array() -= bulge;
  hi.array() += bulge;
}

}  // namespace

void OctomapExportOptions::validate() const {
  require_parameter(occupancy_threshold > 0 && occupancy_threshold < 1, "occupancy_threshold", occupancy_threshold,
                    "in (0, 1)");
  require_parameter(unknown_band_probability >= 0 && unknown_band_probability < 0.5, "unknown_band_probability",
                    unknown_band_probability, "in [0, 0.5)");
  require_parameter(memory_cap_bytes > 0, "memory_cap_bytes", static_cast<double>(memory_cap_bytes), "> 0");
}

std::unique_ptr<octomap::OcTree> make_octree(const SphericalGrid& grid, double resolution_m,
                                             const OctomapExportOptions& options) {
  options.validate();
  require_parameter(std::isfinite(resolution_m) && resolution_m > 0, "resolution_m", resolution_m, "> 0");
  auto tree = std::make_unique<octomap::OcTree>(resolution_m);
  if (grid.clamped()) {
    tree->setClampingThresMin(grid.options().probability_min);
    tree->setClampingThresMax(grid.options().probability_max);
  } else {
    // OctoMap stores thresholds as float log-odds; probabilities 0 and 1 become -inf and +inf, i.e. no
    // clamping, as eq. 2 in exact mode (exact-mode free space reaches log-odds of -1000 and below).
    tree->setClampingThresMin(0.0);
    tree->setClampingThresMax(1.0);
  }
  tree->setOccupancyThres(options.occupancy_threshold);
  return tree;
}

OctomapExportReport add_to_octree(octomap::OcTree& tree, const SphericalGrid& grid,
                                  const Eigen::Isometry3d& world_from_sensor, const OctomapExportOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  options.validate();
  require_rigid(world_from_sensor);
  const SphericalGeometry& geometry = grid.geometry();
  const double resolution = tree.getResolution();

  const double far_m = known_far_m(grid);
  const double volume_m3 = frustum_volume_m3(geometry, far_m);
  const double leaves = volume_m3 / (resolution * resolution * resolution);
  if (leaves * kBytesPerLeaf > static_cast<double>(options.memory_cap_bytes)) {
    std::ostringstream msg;
    msg << "OcTree export at resolution " << resolution << " m: about " << leaves << " leaves ("
        << leaves * kBytesPerLeaf / (1 << 20) << " MiB) in the " << volume_m3
        << " m^3 of known field of view exceed memory_cap_bytes = "
        << static_cast<double>(options.memory_cap_bytes) / (1 << 20) << " MiB; choose a coarser resolution";
    throw ResourceLimit(msg.str());
  }
  Eigen::Vector3d lo, hi;
  frustum_bounds(geometry, far_m, world_from_sensor, lo, hi);
  octomap::OcTreeKey key_lo, key_hi;
  if (!tree.coordToKeyChecked(lo.x(), lo.y(), lo.z(), key_lo) ||
      !tree.coordToKeyChecked(hi.x(), hi.y(), hi.z(), key_hi)) {
    std::ostringstream msg;
    msg << "the field of view seen from this pose spans [" << lo.transpose() << "] .. [" << hi.transpose()
        << "] m, outside the OcTree's addressable range at resolution " << resolution << " m";
    throw InvalidParameter(msg.str());
  }

  const double log_odds_band = logit(0.5 + options.unknown_band_probability);
  const GeometryParams& params = geometry.params();
  const double near2 = params.depth_min_m * params.depth_min_m;
  // Sensor-frame position of a leaf centre: p = R^T (c - t), stepped along world z inside the loop.
  const Eigen::Matrix3d sensor_from_world = world_from_sensor.linear().transpose();
  const Eigen::Vector3d origin = world_from_sensor.translation();
  const Eigen::Vector3d step_z = sensor_from_world.col(2) * resolution;
  GridAccessor accessor(grid);
  OctomapExportReport report;
  octomap::OcTreeKey key;
  for (unsigned kx = key_lo[0]; kx <= key_hi[0]; ++kx) {
    key[0] = static_cast<octomap::key_type>(kx);
    for (unsigned ky = key_lo[1]; ky <= key_hi[1]; ++ky) {
      throw_if_stop_requested();  // a column of leaves along z per poll
      key[1] = static_cast<octomap::key_type>(ky);
      const Eigen::Vector3d first(tree.keyToCoord(key[0]), tree.keyToCoord(key[1]), tree.keyToCoord(key_lo[2]));
      Eigen::Vector3d p = sensor_from_world * (first - origin);
      for (unsigned kz = key_lo[2]; kz <= key_hi[2]; ++kz, p += step_z) {
        ++report.leaves_examined;
        // The depth coordinate (range or z) is at most the range: leaves nearer than the grid start are out.
        const double rho2 = p.squaredNorm();
        if (rho2 < near2 || rho2 == 0.0) continue;
        RayPosition ray;
        if (!geometry.project(p.x(), p.y(), p.z(), ray) || ray.depth >= far_m) continue;
        const int bin = geometry.depth().bin(ray.depth);
        if (bin < 0 || bin >= geometry.depth().bins()) continue;
        const float value = accessor.log_odds(geometry.column(ray.horizontal_bin, ray.vertical_bin), bin);
        if (std::abs(value) < log_odds_band) {
          ++report.left_unknown;
          continue;
        }
        key[2] = static_cast<octomap::key_type>(kz);
        const octomap::OcTreeNode* node = tree.updateNode(key, value, true);
        (tree.isNodeOccupied(node) ? report.occupied_written : report.free_written) += 1;
      }
    }
  }
  // Lazy insertion leaves inner nodes stale and every leaf expanded: refresh the inner nodes, then merge
  // children of equal value (uniform free space at the clamp) as OctoMap's own insertion does.
  tree.updateInnerOccupancy();
  tree.prune();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

std::unique_ptr<octomap::OcTree> to_octree(const SphericalGrid& grid, const Eigen::Isometry3d& world_from_sensor,
                                           double resolution_m, const OctomapExportOptions& options,
                                           OctomapExportReport* report) {
  auto tree = make_octree(grid, resolution_m, options);
  const OctomapExportReport r = add_to_octree(*tree, grid, world_from_sensor, options);
  if (report) *report = r;
  return tree;
}

void require_octomap_output_path(const std::string& path) {
  const std::string extension = std::filesystem::path(path).extension().string();
  if (extension != ".bt" && extension != ".ot")
    throw InvalidParameter("OctoMap output '" + path + "' must end in .bt (maximum likelihood) or .ot (full)");
}

void write_octree(const octomap::OcTree& tree, const std::string& path) {
  require_octomap_output_path(path);
  const bool full = std::filesystem::path(path).extension() == ".ot";
  write_file_atomically(path, "OctoMap file", [&](std::ostream& out) {
    return full ? tree.write(out) : tree.writeBinaryConst(out);
  });
}

}  // namespace occ_improve
