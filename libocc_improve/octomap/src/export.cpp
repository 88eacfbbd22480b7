#include "occ_improve/octomap/export.hpp"

#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/maps/surface.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "occ_improve/geometry/rotation.hpp"
#include "occ_improve/timing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <utility>
#include <vector>

namespace occ_improve {
namespace {

using detail::require_parameter;

// Memory of one OcTree leaf: the node (float + children pointer, 16 bytes) plus its share of the parent's
// 8-pointer child array (8 bytes), plus ~1/7 for the inner levels above. Used only for the cap estimate.
constexpr double kBytesPerLeaf = 28.0;

// The pose as a rigid transform: a rotation written with 7-8 digits (7-Scenes': |R^T R - I| = 1.5e-4, refused
// before) is taken as the nearest rotation, as the tools read pose files (geometry/rotation.hpp).
Eigen::Isometry3d rigid_pose(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d& m = pose.matrix();
  if (const std::optional<Eigen::Isometry3d> rigid = rigid_transform(m)) return *rigid;
  if (!m.allFinite()) throw InvalidParameter("pose (world <- sensor) has non-finite entries");
  if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
    throw InvalidParameter("pose (world <- sensor) is not an affine transform: last row must be 0 0 0 1");
  std::ostringstream msg;
  msg << "pose (world <- sensor) is not a rigid transform: its 3x3 part is no rotation within " << kRotationTolerance
      << ", det R = " << m.topLeftCorner<3, 3>().determinant() << " (scaling, shear or reflection)";
  throw InvalidParameter(msg.str());
}

// The far end of everything the grid knows: beyond the last touched bin of every column all voxels are
// unknown, so the export need not visit them (a table-top frame in an 8 m grid ends near 2 m).
double known_far_m(const ColumnGrid& grid) {
  const GridGeometry& g = grid.geometry();
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
void for_each_lattice_position(const GridGeometry& g, Visit&& visit) {
  const BinAxis &h = g.azimuth(), &v = g.elevation();
  for (int i = 0; i < kSamples; ++i)
    for (int j = 0; j < kSamples; ++j)
      visit(i, j, h.min() + i * (h.max() - h.min()) / (kSamples - 1), v.min() + j * (v.max() - v.min()) / (kSamples - 1));
}

// Volume of the field of view out to depth coordinate far_m: per lattice cell, its solid angle (the
// parallelogram of two edge directions) x (r_far^3 - r_near^3) / 3 at the cell's first corner. An
// estimate for the memory cap only.
double frustum_volume_m3(const GridGeometry& g, double far_m) {
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
void frustum_bounds(const GridGeometry& g, double far_m, const Eigen::Isometry3d& pose, Eigen::Vector3d& lo,
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


// ---- What the grid's voxels say about the leaves they reach (the conversion rule in export.hpp) ----

enum class VoxelClass { unknown, free, occupied };

// Occupied and free: evidence outside the unknown band. An untouched voxel (log-odds exactly 0) is unknown
// even with a zero band.
VoxelClass classify(float log_odds, float band) {
  if (log_odds > 0 && log_odds >= band) return VoxelClass::occupied;
  if (log_odds < 0 && log_odds <= -band) return VoxelClass::free;
  return VoxelClass::unknown;
}

struct LeafMark {
  float occupied_log_odds = -std::numeric_limits<float>::infinity();  ///< max over occupied voxels reaching it
  bool free_boundary = false;  ///< a face between free and not-free space reaches it
  /// A column's surface voxel (its return, as far as the grid knows) that is not occupied reaches it:
  /// neighbouring rays' free space carved it (depth edges). Where a free-space boundary also reaches the
  /// leaf, FreeLeafRule::crossed does not write it free from a free corner, as OctoMap never frees a leaf
  /// holding an endpoint (a leaf no boundary reaches is one class of space: free when its centre is).
  bool carved_surface = false;
  bool occupied() const { return occupied_log_odds > -std::numeric_limits<float>::infinity(); }
  bool marked() const { return free_boundary || carved_surface || occupied(); }
};

// The marks of the leaves in the key box [lo, hi], in blocks of 8 x 8 x 8 leaves allocated on first touch:
// marks gather along surfaces and free-space boundaries, and consecutive pieces of a column reach the same
// block (a hash map of leaf keys spent most of the export chasing cache misses).
class LeafMarks {
public:
  LeafMarks(const octomap::OcTreeKey& lo, const octomap::OcTreeKey& hi) : lo_(lo) {
    for (int axis = 0; axis < 3; ++axis) blocks_[axis] = (hi[axis] - lo[axis]) / kBlock + 1;
    table_.resize(static_cast<std::size_t>(blocks_[0]) * blocks_[1] * blocks_[2]);
  }

  /// The mark of a leaf inside the box, its block allocated when needed.
  LeafMark& at(const octomap::OcTreeKey& key) {
    std::size_t slot;
    std::unique_ptr<Block>& block = table_[locate(key, slot)];
    if (!block) block = std::make_unique<Block>();
    return block->marks[slot];
  }
  /// nullptr when the leaf was never marked.
  const LeafMark* find(const octomap::OcTreeKey& key) const {
    std::size_t slot;
    const std::unique_ptr<Block>& block = table_[locate(key, slot)];
    return block && block->marks[slot].marked() ? &block->marks[slot] : nullptr;
  }
  template <typename Visit>
  void for_each_occupied(Visit&& visit) const {
    for (std::size_t b = 0; b < table_.size(); ++b) {
      if (!table_[b]) continue;
      const unsigned bx = static_cast<unsigned>(b % blocks_[0]), by = static_cast<unsigned>(b / blocks_[0] % blocks_[1]),
                     bz = static_cast<unsigned>(b / blocks_[0] / blocks_[1]);
      for (unsigned slot = 0; slot < kBlock * kBlock * kBlock; ++slot) {
        const LeafMark& mark = table_[b]->marks[slot];
        if (!mark.occupied()) continue;
        octomap::OcTreeKey key;
        key[0] = static_cast<octomap::key_type>(lo_[0] + bx * kBlock + slot % kBlock);
        key[1] = static_cast<octomap::key_type>(lo_[1] + by * kBlock + slot / kBlock % kBlock);
        key[2] = static_cast<octomap::key_type>(lo_[2] + bz * kBlock + slot / (kBlock * kBlock));
        visit(key, mark.occupied_log_odds);
      }
    }
  }

private:
  static constexpr unsigned kBlock = 8;
  struct Block {
    LeafMark marks[kBlock * kBlock * kBlock];
  };
  std::size_t locate(const octomap::OcTreeKey& key, std::size_t& slot) const {
    const unsigned x = key[0] - lo_[0], y = key[1] - lo_[1], z = key[2] - lo_[2];
    slot = (x % kBlock) + kBlock * ((y % kBlock) + kBlock * (z % kBlock));
    return (x / kBlock) + blocks_[0] * ((y / kBlock) + static_cast<std::size_t>(blocks_[1]) * (z / kBlock));
  }
  octomap::OcTreeKey lo_;
  unsigned blocks_[3];
  std::vector<std::unique_ptr<Block>> table_;
};

// A piece of the grid in the world frame: the points origin + d q for the depth coordinate d in [near, far]
// (near >= 0) and directions q in the box [q_lo, q_hi]. Directions are world-frame vectors scaled so that d is
// the depth coordinate (unit vectors for the spherical binning, sensor z = 1 for the pinhole one); the box
// of a few column corners' directions holds a run of voxels, a cap (near == far) or a strip of faces
// between columns.
struct Patch {
  Eigen::Vector3d q_lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d q_hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  double near = 0, far = 0;

  void include(const Eigen::Vector3d& q) {
    q_lo = q_lo.cwiseMin(q);
    q_hi = q_hi.cwiseMax(q);
  }
  void include(const Patch& other) {
    q_lo = q_lo.cwiseMin(other.q_lo);
    q_hi = q_hi.cwiseMax(other.q_hi);
  }
  /// Extent across the rays at depth coordinate d (the box's diagonal).
  double width_at(double d) const { return (q_hi - q_lo).norm() * d; }
};

// The leaves a patch reaches, conservatively: the patch is cut along its depth into pieces at most step_m
// long, and every leaf meeting a piece's axis-aligned box (padded by pad_m) is visited. For d >= 0 the box
// of {d q} over the piece's depths and the direction box is the box of its corner points; a pinhole voxel,
// cap or face is the convex hull of its corner points, and the curved faces of a spherical one bulge out of
// that box by less than pad_m. So a leaf is visited only where the patch passes within
// max(step_m, the patch's width) of it.
class PatchCover {
public:
  PatchCover(const octomap::OcTree& tree, const Eigen::Vector3d& origin, const octomap::OcTreeKey& lo,
             const octomap::OcTreeKey& hi, double step_m, double pad_m)
      : tree_(tree), origin_(origin), lo_(lo), hi_(hi), step_m_(step_m), pad_m_(pad_m) {}

  double step_m() const { return step_m_; }
  const octomap::OcTreeKey& key_lo() const { return lo_; }
  const octomap::OcTreeKey& key_hi() const { return hi_; }

  template <typename Visit>
  void for_each_leaf(const Patch& p, Visit&& visit) const {
    const double ray_length = p.q_lo.cwiseAbs().cwiseMax(p.q_hi.cwiseAbs()).norm();  // per unit depth, at most
    const int pieces = std::max(1, static_cast<int>(std::ceil((p.far - p.near) * ray_length / step_m_)));
    for (int k = 0; k < pieces; ++k) {
      const double d0 = p.near + (p.far - p.near) * k / pieces;
      const double d1 = k + 1 == pieces ? p.far : p.near + (p.far - p.near) * (k + 1) / pieces;
      visit_box(origin_ + (d0 * p.q_lo).cwiseMin(d1 * p.q_lo), origin_ + (d0 * p.q_hi).cwiseMax(d1 * p.q_hi), visit);
    }
  }

private:
  template <typename Visit>
  void visit_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Visit& visit) const {
    unsigned first[3], last[3];
    for (int axis = 0; axis < 3; ++axis) {
      first[axis] = std::max<unsigned>(lo_[axis], tree_.coordToKey(lo[axis] - pad_m_));
      last[axis] = std::min<unsigned>(hi_[axis], tree_.coordToKey(hi[axis] + pad_m_));
      if (first[axis] > last[axis]) return;
    }
    octomap::OcTreeKey key;
    for (unsigned x = first[0]; x <= last[0]; ++x)
      for (unsigned y = first[1]; y <= last[1]; ++y)
        for (unsigned z = first[2]; z <= last[2]; ++z) {
          key[0] = static_cast<octomap::key_type>(x);
          key[1] = static_cast<octomap::key_type>(y);
          key[2] = static_cast<octomap::key_type>(z);
          visit(key);
        }
  }

  const octomap::OcTree& tree_;
  Eigen::Vector3d origin_;
  octomap::OcTreeKey lo_, hi_;
  double step_m_, pad_m_;
};

// Bins [first, end) of one column.
struct BinRun {
  int first, end;
};

// Walks the grid and marks the leaves its occupied voxels and its free-space boundaries reach. The
// boundary of the free space is made of caps (where a column's free run starts or ends) and of faces
// between neighbouring columns (over the depths where exactly one of the two is free; outside the grid is
// unknown). Caps at the same bin in neighbouring columns of a row, and faces along one edge line, are
// gathered into patches no wider than the cover's step: far fewer boxes, no looser than the step.
class LeafMarker {
public:
  LeafMarker(const ColumnGrid& grid, const Eigen::Isometry3d& world_from_sensor, float band, FreeLeafRule rule,
             const PatchCover& cover)
      : grid_(grid), g_(grid.geometry()), band_(band), rule_(rule), cover_(cover), marks_(cover.key_lo(), cover.key_hi()),
        corners_(static_cast<std::size_t>(g_.width() + 1) * (g_.height() + 1)) {
    const Eigen::Matrix3d rotation = world_from_sensor.linear();
    for (int v = 0; v <= g_.height(); ++v)
      for (int h = 0; h <= g_.width(); ++h)
        corners_[corner_index(h, v)] = rotation * g_.point_at(g_.azimuth().lower(h), g_.elevation().lower(v), 1.0);
  }

  LeafMarks mark() {
    first_run_.reserve(g_.column_count() + 1);
    for (int v = 0; v < g_.height(); ++v) {
      throw_if_stop_requested();  // a row of columns per poll
      for (int h = 0; h < g_.width(); ++h) {
        first_run_.push_back(static_cast<std::uint32_t>(runs_.size()));
        if (const ColumnData* column = grid_.find(g_.column(h, v))) scan_column(h, v, *column);
        close_caps_before(h);
      }
      close_caps_before(g_.width());
    }
    first_run_.push_back(static_cast<std::uint32_t>(runs_.size()));
    mark_lateral_faces();
    return std::move(marks_);
  }

private:
  struct OpenCap {  ///< caps at one bin in consecutive columns of the row being scanned
    int bin, last_h;
    Patch patch;
  };
  struct Strip {  ///< faces along one edge line, gathered
    bool open = false;
    Patch patch;
    int end = 0;  ///< largest end bin of its runs
    std::vector<BinRun> runs;
  };

  std::size_t corner_index(int h, int v) const { return static_cast<std::size_t>(v) * (g_.width() + 1) + h; }
  const Eigen::Vector3d& corner(int h, int v) const { return corners_[corner_index(h, v)]; }
  double depth_at(int bin) const { return g_.depth().lower(bin); }  // a bin's near edge; bins() gives the far end

  Patch column_patch(int h, int v) const {
    Patch p;
    for (int dv = 0; dv <= 1; ++dv)
      for (int dh = 0; dh <= 1; ++dh) p.include(corner(h + dh, v + dv));
    return p;
  }

  void mark_boundary(const Patch& p) {
    cover_.for_each_leaf(p, [&](const octomap::OcTreeKey& key) { marks_.at(key).free_boundary = true; });
  }
  void mark_occupied(const Patch& p, float log_odds) {
    cover_.for_each_leaf(p, [&](const octomap::OcTreeKey& key) {
      float& value = marks_.at(key).occupied_log_odds;
      value = std::max(value, log_odds);
    });
  }

  // One column's stored bins (uniform run, then window; the tail is unknown): occupied voxels grouped into
  // runs no deeper than the cover's step, each carrying its largest log-odds; a cap wherever free space
  // starts or ends next to unknown space (next to an occupied voxel the voxel's own box holds the cap); the
  // free runs kept for the faces between columns.
  void scan_column(int h, int v, const ColumnData& column) {
    const int end = std::min(column.window_end(), g_.depth().bins());
    Patch patch = column_patch(h, v);
    if (rule_ == FreeLeafRule::crossed) mark_carved_surface(patch, column);
    const double ray_length = patch.q_lo.cwiseAbs().cwiseMax(patch.q_hi.cwiseAbs()).norm();
    VoxelClass previous = VoxelClass::unknown;
    int free_first = 0, group_first = -1, group_end = 0;
    float group_max = 0;
    const auto close_group = [&] {
      if (group_first < 0) return;
      patch.near = depth_at(group_first);
      patch.far = depth_at(group_end);
      mark_occupied(patch, group_max);
      group_first = -1;
    };
    const auto block = [&](int first, int block_end, VoxelClass c, float log_odds) {
      if ((c == VoxelClass::free) != (previous == VoxelClass::free)) {
        if (c != VoxelClass::occupied && previous != VoxelClass::occupied) add_cap(h, v, first);
        if (c == VoxelClass::free) free_first = first;
        else runs_.push_back({free_first, first});
      }
      previous = c;
      if (c != VoxelClass::occupied) return close_group();
      if (group_first >= 0 && (depth_at(block_end) - depth_at(group_first)) * ray_length > cover_.step_m()) close_group();
      if (group_first < 0) {
        group_first = first;
        group_max = log_odds;
      }
      group_max = std::max(group_max, log_odds);
      group_end = block_end;
    };
    const int uniform_end = std::min(column.uniform_end, end);
    if (uniform_end > 0) block(0, uniform_end, classify(column.uniform_value, band_), column.uniform_value);
    for (int b = uniform_end; b < end; ++b) {
      const float value = column.window[static_cast<std::size_t>(b - uniform_end)];
      block(b, b + 1, classify(value, band_), value);
    }
    block(end, end, VoxelClass::unknown, 0.0f);  // the unknown tail (or the grid's far end)
  }

  // The column's surface voxel when it is not occupied (LeafMark::carved_surface).
  void mark_carved_surface(Patch patch, const ColumnData& column) {
    const SurfaceVoxel surface = column_surface(column.contents(), grid_);
    if (surface.unknown || surface.bin < 0 || surface.bin >= g_.depth().bins()) return;  // none, or free to the end
    if (classify(column.value(surface.bin), band_) == VoxelClass::occupied) return;  // marked as occupied
    patch.near = depth_at(surface.bin);
    patch.far = depth_at(surface.bin + 1);
    cover_.for_each_leaf(patch, [&](const octomap::OcTreeKey& key) { marks_.at(key).carved_surface = true; });
  }

  // A cap at `bin` of column (h, v): joins the row's open cap at that bin when that ended at column h - 1
  // and stays within the step.
  void add_cap(int h, int v, int bin) {
    const Patch column = column_patch(h, v);
    const double depth = depth_at(bin);
    for (OpenCap& cap : open_caps_) {
      if (cap.bin != bin || cap.last_h != h - 1) continue;
      Patch joined = cap.patch;
      joined.include(column);
      if (joined.width_at(depth) <= cover_.step_m()) {
        cap.patch = joined;
        cap.last_h = h;
        return;
      }
    }
    OpenCap cap{bin, h, column};
    cap.patch.near = cap.patch.far = depth;
    open_caps_.push_back(cap);
  }
  // Marks the caps that did not reach column h.
  void close_caps_before(int h) {
    const auto closed = std::partition(open_caps_.begin(), open_caps_.end(), [&](const OpenCap& c) { return c.last_h >= h; });
    for (auto it = closed; it != open_caps_.end(); ++it) mark_boundary(it->patch);
    open_caps_.erase(closed, open_caps_.end());
  }

  std::pair<const BinRun*, const BinRun*> free_runs(int h, int v) const {
    if (h < 0 || v < 0 || h >= g_.width() || v >= g_.height()) return {nullptr, nullptr};  // outside: unknown
    const std::size_t c = g_.column(h, v);
    return {runs_.data() + first_run_[c], runs_.data() + first_run_[c + 1]};
  }

  void mark_lateral_faces() {
    Strip strip;
    for (int h = 0; h <= g_.width(); ++h) {  // edges between columns h - 1 and h, along v
      throw_if_stop_requested();
      for (int v = 0; v < g_.height(); ++v) add_face(strip, free_runs(h - 1, v), free_runs(h, v), corner(h, v), corner(h, v + 1));
      close_strip(strip);
    }
    for (int v = 0; v <= g_.height(); ++v) {  // edges between rows v - 1 and v, along h
      throw_if_stop_requested();
      for (int h = 0; h < g_.width(); ++h) add_face(strip, free_runs(h, v - 1), free_runs(h, v), corner(h, v), corner(h + 1, v));
      close_strip(strip);
    }
  }

  // The face between two neighbouring columns (edge e0-e1) over the bins where exactly one is free, added to
  // the strip along this edge line while the strip stays within the step.
  void add_face(Strip& strip, std::pair<const BinRun*, const BinRun*> a, std::pair<const BinRun*, const BinRun*> b,
                const Eigen::Vector3d& e0, const Eigen::Vector3d& e1) {
    difference_.clear();
    if (a.first != a.second || b.first != b.second) symmetric_difference(a, b, difference_);
    if (difference_.empty()) return close_strip(strip);
    Patch edge;
    edge.include(e0);
    edge.include(e1);
    const int end = std::max(strip.open ? strip.end : 0, difference_.back().end);
    if (strip.open) {
      Patch joined = strip.patch;
      joined.include(edge);
      if (joined.width_at(depth_at(end)) > cover_.step_m()) close_strip(strip);
    }
    if (!strip.open) {
      strip.open = true;
      strip.patch = edge;
      strip.end = 0;
    }
    strip.patch.include(edge);
    strip.end = std::max(strip.end, difference_.back().end);
    strip.runs.insert(strip.runs.end(), difference_.begin(), difference_.end());
  }

  // Marks a strip over the union of its runs.
  void close_strip(Strip& strip) {
    if (!strip.open) return;
    std::sort(strip.runs.begin(), strip.runs.end(), [](const BinRun& x, const BinRun& y) { return x.first < y.first; });
    Patch face = strip.patch;
    for (std::size_t i = 0; i < strip.runs.size();) {
      int first = strip.runs[i].first, end = strip.runs[i].end;
      for (++i; i < strip.runs.size() && strip.runs[i].first <= end; ++i) end = std::max(end, strip.runs[i].end);
      face.near = depth_at(first);
      face.far = depth_at(end);
      mark_boundary(face);
    }
    strip.runs.clear();
    strip.open = false;
  }

  // Bins inside exactly one of two sorted lists of disjoint runs, as sorted runs.
  void symmetric_difference(std::pair<const BinRun*, const BinRun*> a, std::pair<const BinRun*, const BinRun*> b,
                            std::vector<BinRun>& out) {
    edges_.clear();
    for (const BinRun* r = a.first; r != a.second; ++r) edges_.insert(edges_.end(), {r->first, r->end});
    for (const BinRun* r = b.first; r != b.second; ++r) edges_.insert(edges_.end(), {r->first, r->end});
    std::sort(edges_.begin(), edges_.end());
    const auto inside = [](std::pair<const BinRun*, const BinRun*> runs, int bin) {
      for (const BinRun* r = runs.first; r != runs.second; ++r)
        if (bin >= r->first && bin < r->end) return true;
      return false;
    };
    int open = -1;  // first bin of the run being built
    for (int bin : edges_) {
      const bool differs = inside(a, bin) != inside(b, bin);
      if (differs && open < 0) open = bin;
      if (!differs && open >= 0) {
        out.push_back({open, bin});
        open = -1;
      }
    }
  }

  const ColumnGrid& grid_;
  const GridGeometry& g_;
  float band_;
  FreeLeafRule rule_;
  const PatchCover& cover_;
  LeafMarks marks_;
  std::vector<Eigen::Vector3d> corners_;  ///< (width + 1) x (height + 1) column-corner directions, world frame
  std::vector<BinRun> runs_;              ///< free runs of every column, in column order
  std::vector<std::uint32_t> first_run_;  ///< per column, its first run in runs_ (and one past the end)
  std::vector<OpenCap> open_caps_;
  std::vector<BinRun> difference_;
  std::vector<int> edges_;
};

// Patches are cut into pieces at most this fraction of a leaf long: a leaf is marked occupied, or not wholly
// free, when an occupied voxel or a free-space boundary passes within this distance of it (export.hpp).
constexpr double kPieceFraction = 0.25;

// How far the curved faces of a spherical voxel (range caps, elevation cones) and the directions between its
// corners stray from the corners' box: less than r alpha^2 / 8 for a column alpha wide (diagonally) at range
// r, taken 4 times over. A binning whose depth is z (pinhole) has plane faces: alpha = 0. Plus a nanometre
// for rounding.
double curvature_pad_m(const GridGeometry& g, double far_m) {
  const double alpha = g.binning().curvature_angle_rad();
  if (alpha == 0) return 1e-9;
  return 1e-9 + far_m * alpha * alpha / 2;
}

// The free leaves (export.hpp's rule). A leaf no free-space boundary reaches holds one class of space: it is
// free when the voxel holding its centre is, and takes that voxel's log-odds. A leaf a boundary reaches
// (and no occupied voxel, no carved surface) is free under FreeLeafRule::crossed when its centre or one of
// its corners lies in a free voxel: it takes the centre's log-odds, else the largest of the free corners'.
// Leaves whose centre is in the field of view and that are neither free nor occupied count as unknown.
class FreeLeafWriter {
public:
  FreeLeafWriter(const octomap::OcTree& tree, const ColumnGrid& grid, const Eigen::Isometry3d& world_from_sensor,
                 double far_m, float band, FreeLeafRule rule)
      : g_(grid.geometry()), accessor_(grid), far_m_(far_m), band_(band), rule_(rule),
        near2_(g_.params().depth_min_m * g_.params().depth_min_m) {
    // Corners a hair inside the leaf: a corner on a face would belong to the next leaf as much as to this one.
    const double half = 0.5 * tree.getResolution() * (1.0 - 1e-6);
    const Eigen::Matrix3d sensor_from_world = world_from_sensor.linear().transpose();
    for (int c = 0; c < 8; ++c)
      corners_[c] = sensor_from_world * Eigen::Vector3d(c & 1 ? half : -half, c & 2 ? half : -half, c & 4 ? half : -half);
  }

  /// The log-odds to write for the leaf centred at sensor-frame `p` with `mark` (nullptr: unmarked), or
  /// nothing; `in_view` tells whether its centre lies in the known field of view.
  std::optional<float> free_value(const Eigen::Vector3d& p, const LeafMark* mark, bool& in_view) {
    std::optional<float> centre = sample(p, in_view);
    if (!mark) return centre;
    if (mark->occupied()) return std::nullopt;
    if (!mark->free_boundary) return centre;  // one class of space throughout, a carved surface in it or not
    if (rule_ == FreeLeafRule::wholly_free || mark->carved_surface) return std::nullopt;
    if (centre) return centre;
    std::optional<float> best;
    for (const Eigen::Vector3d& corner : corners_) {
      bool corner_in_view;
      const std::optional<float> value = sample(p + corner, corner_in_view);
      if (value && (!best || *value > *best)) best = value;
    }
    return best;
  }

private:
  // The log-odds of the free voxel holding sensor-frame point q, or nothing (not free, not in the grid).
  std::optional<float> sample(const Eigen::Vector3d& q, bool& in_view) {
    in_view = false;
    // The depth coordinate (range or z) is at most the range: points nearer than the grid start are out.
    const double rho2 = q.squaredNorm();
    if (rho2 < near2_ || rho2 == 0.0) return std::nullopt;
    RayPosition ray;
    if (!g_.project(q.x(), q.y(), q.z(), ray) || ray.depth >= far_m_) return std::nullopt;
    const int bin = g_.depth().bin(ray.depth);
    if (bin < 0 || bin >= g_.depth().bins()) return std::nullopt;
    in_view = true;
    const float value = accessor_.log_odds(g_.column(ray.horizontal_bin, ray.vertical_bin), bin);
    if (classify(value, band_) != VoxelClass::free) return std::nullopt;
    return value;
  }

  const GridGeometry& g_;
  GridAccessor accessor_;
  const double far_m_;
  const float band_;
  const FreeLeafRule rule_;
  const double near2_;
  Eigen::Vector3d corners_[8];
};

template <typename Write>
void write_free_leaves(const octomap::OcTree& tree, const ColumnGrid& grid, const Eigen::Isometry3d& world_from_sensor,
                       double far_m, const octomap::OcTreeKey& key_lo, const octomap::OcTreeKey& key_hi, float band,
                       FreeLeafRule rule, const LeafMarks& marks, Write&& write, OctomapExportReport& report) {
  const Eigen::Matrix3d sensor_from_world = world_from_sensor.linear().transpose();
  const Eigen::Vector3d origin = world_from_sensor.translation();
  // Loop order: innermost along the world axis nearest the sensor's x (neighbouring columns of one row lie
  // side by side in the grid's tiles), then the one nearest its depth axis; a fixed x-y-z order stepped
  // across image rows and missed the cache on nearly every column lookup.
  int inner = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(sensor_from_world(2, a)) > std::abs(sensor_from_world(2, inner))) inner = a;
  const int a1 = (inner + 1) % 3, a2 = (inner + 2) % 3;
  const int middle = std::abs(sensor_from_world(0, a1)) >= std::abs(sensor_from_world(0, a2)) ? a1 : a2;
  const int outer = 3 - inner - middle;
  // Sensor-frame position of a leaf centre: p = R^T (c - t), stepped along the inner axis.
  const Eigen::Vector3d step = sensor_from_world.col(inner) * tree.getResolution();
  FreeLeafWriter writer(tree, grid, world_from_sensor, far_m, band, rule);
  octomap::OcTreeKey key;
  for (unsigned ko = key_lo[outer]; ko <= key_hi[outer]; ++ko) {
    key[outer] = static_cast<octomap::key_type>(ko);
    for (unsigned km = key_lo[middle]; km <= key_hi[middle]; ++km) {
      throw_if_stop_requested();  // a line of leaves per poll
      key[middle] = static_cast<octomap::key_type>(km);
      key[inner] = key_lo[inner];
      const Eigen::Vector3d first(tree.keyToCoord(key[0]), tree.keyToCoord(key[1]), tree.keyToCoord(key[2]));
      Eigen::Vector3d p = sensor_from_world * (first - origin);
      for (unsigned ki = key_lo[inner]; ki <= key_hi[inner]; ++ki, p += step) {
        ++report.leaves_examined;
        key[inner] = static_cast<octomap::key_type>(ki);
        const LeafMark* mark = marks.find(key);
        if (mark && mark->occupied()) continue;  // written already
        bool in_view;
        if (const std::optional<float> value = writer.free_value(p, mark, in_view)) {
          write(key, *value);
        } else if (in_view) {
          ++report.left_unknown;
        }
      }
    }
  }
}

// OccupancyOcTreeBase::updateInnerOccupancy and OcTreeBaseImpl::prune as OctoMap 1.9 does them (the same
// recursions; prune's level by level from the deepest up, stopping at the first level that prunes
// nothing), polling for a stop every 65536 nodes (update_inner_occupancy_and_prune; tests/octomap checks
// the trees are the same as OctoMap's own calls make).
class PollingTreeFinish {
public:
  explicit PollingTreeFinish(octomap::OcTree& tree) : tree_(tree) {}

  void update_inner_occupancy() {
    if (tree_.getRoot()) update_inner(tree_.getRoot(), 0);
  }
  void prune() {
    if (!tree_.getRoot()) return;
    for (unsigned depth = tree_.getTreeDepth() - 1; depth > 0; --depth) {
      std::size_t pruned = 0;
      prune_level(tree_.getRoot(), 0, depth, pruned);
      if (pruned == 0) break;
    }
  }

private:
  // Every 65536 nodes: a poll, and one allocation of a few KB. glibc's malloc keeps freed small chunks (the
  // pruned nodes) in fast bins until an allocation of that size merges them all at once: after pruning
  // 10^7 nodes the next one, wherever it falls (the output's directory listing), took 0.5 s deaf to
  // Ctrl-C. Asking here merges them a poll's worth at a time, for the same total.
  void visit() {
    if (++visited_ % (1 << 16) != 0) return;
    throw_if_stop_requested();
    void* volatile block = std::malloc(4096);  // volatile: a compiler may drop an unused allocation
    std::free(block);
  }
  void update_inner(octomap::OcTreeNode* node, unsigned depth) {
    if (!tree_.nodeHasChildren(node)) return;
    visit();
    if (depth < tree_.getTreeDepth())
      for (unsigned i = 0; i < 8; ++i)
        if (tree_.nodeChildExists(node, i)) update_inner(tree_.getNodeChild(node, i), depth + 1);
    node->updateOccupancyChildren();
  }
  void prune_level(octomap::OcTreeNode* node, unsigned depth, unsigned max_depth, std::size_t& pruned) {
    visit();
    if (depth < max_depth) {
      for (unsigned i = 0; i < 8; ++i)
        if (tree_.nodeChildExists(node, i)) prune_level(tree_.getNodeChild(node, i), depth + 1, max_depth, pruned);
    } else if (tree_.pruneNode(node)) {
      ++pruned;
    }
  }

  octomap::OcTree& tree_;
  std::size_t visited_ = 0;
};

// The line by which a tree file says occ_improve wrote it (is_octomap_file), right after OctoMap's first
// line: OctoMap's readers skip comment lines there, so every OctoMap reader still reads the file.
constexpr const char* kWrittenByLine = "# written by occ_improve";

// The data OctoMap's own writeBinary() writes (toMaxLikelihood(), prune(), then writeBinaryData), computed
// without changing the tree: every node in its maximum-likelihood state (occupied or free), and the children
// that prune() would merge written as one leaf. prune() works level by level from the deepest up and stops
// at the first level where nothing merges, so a first pass counts, per depth, the nodes that would merge
// (all 8 children leaves of one state once the levels below are merged); merging happens from the
// deepest level up to the one above the first without any. The second pass writes each node's two bytes
// of child codes (OccupancyOcTreeBase::writeBinaryNode's: 01 occupied, 10 free, 11 inner, 00 absent) and
// its children after them, dropping the bytes of a child that merges. Both poll for a stop.
class MaxLikelihoodBinary {
public:
  explicit MaxLikelihoodBinary(const octomap::OcTree& tree) : tree_(tree), merging_(tree.getTreeDepth(), 0) {
    if (!tree.getRoot()) return;
    count_merging(tree.getRoot(), 0);
    merge_from_ = 1;  // prune() never merges the root
    for (unsigned depth = tree.getTreeDepth() - 1; depth > 0; --depth)
      if (merging_[depth] == 0) {
        merge_from_ = depth + 1;
        break;
      }
    nodes_ = 1 + encode(tree.getRoot(), 0).nodes;
  }
  std::size_t size() const { return nodes_; }  ///< nodes of the pruned tree (the header's "size")
  void write(std::ostream& out) const { out.write(bytes_.data(), static_cast<std::streamsize>(bytes_.size())); }

private:
  enum class State { free, occupied, mixed };
  struct Encoded {
    State state;        ///< the node's, were it merged: its children's common leaf state, or mixed
    std::size_t nodes;  ///< nodes written below it
  };

  // The state 8 children share once merged (each a leaf of that state), or mixed: what their parent
  // merges into (a missing child keeps it from merging).
  struct SharedState {
    State state = State::mixed;
    bool shared = true;
    void absent() { shared = false; }
    void add(unsigned child, State s) {
      if (child == 0) state = s;
      shared = shared && s != State::mixed && s == state;
    }
    State result() const { return shared ? state : State::mixed; }
  };

  State leaf_state(const octomap::OcTreeNode* node) const {
    return tree_.isNodeOccupied(node) ? State::occupied : State::free;
  }
  void visit() {
    if (++visited_ % (1 << 16) == 0) throw_if_stop_requested();
  }
  // The node's state once every level below is merged; counts the inner nodes that merge, per depth.
  State count_merging(const octomap::OcTreeNode* node, unsigned depth) {
    visit();
    if (!tree_.nodeHasChildren(node)) return leaf_state(node);
    SharedState children;
    for (unsigned i = 0; i < 8; ++i) {
      if (tree_.nodeChildExists(node, i))
        children.add(i, count_merging(tree_.getNodeChild(node, i), depth + 1));
      else
        children.absent();
    }
    if (children.result() != State::mixed) ++merging_[depth];
    return children.result();
  }
  Encoded encode(const octomap::OcTreeNode* node, unsigned depth) {
    visit();
    const std::size_t at = bytes_.size();
    bytes_.resize(at + 2);
    unsigned codes = 0;  // 2 bits per child, child 0 in the lowest: OctoMap's two bitsets
    std::size_t nodes = 0;
    SharedState children;
    for (unsigned i = 0; i < 8; ++i) {
      if (!tree_.nodeChildExists(node, i)) {
        children.absent();
        continue;
      }
      const octomap::OcTreeNode* child = tree_.getNodeChild(node, i);
      State leaf = State::mixed;
      nodes += 1;
      if (!tree_.nodeHasChildren(child)) {
        leaf = leaf_state(child);
      } else {
        const std::size_t child_at = bytes_.size();
        const Encoded below = encode(child, depth + 1);
        if (depth + 1 >= merge_from_ && below.state != State::mixed) {
          bytes_.resize(child_at);  // merged into a leaf: its children are not written
          leaf = below.state;
        } else {
          nodes += below.nodes;
        }
      }
      const unsigned code = leaf == State::occupied ? 2u : leaf == State::free ? 1u : 3u;  // bit 2i first
      codes |= code << (2 * i);
      children.add(i, leaf);
    }
    bytes_[at] = static_cast<char>(codes & 0xff);
    bytes_[at + 1] = static_cast<char>(codes >> 8);
    return {children.result(), nodes};
  }

  const octomap::OcTree& tree_;
  std::vector<std::size_t> merging_;  ///< per depth, the inner nodes that merge
  unsigned merge_from_ = 1;           ///< the shallowest depth that merges
  std::vector<char> bytes_;
  std::size_t nodes_ = 0;
  std::size_t visited_ = 0;
};

// OctoMap's file headers, written here: with our line, and because Debian's liboctomap prints " done." to
// stderr after every binary write (issue 18: before a tool's error line). The headers are OctoMap's, byte for
// byte, but for that line. .bt: the data of OctoMap's writeBinary() (MaxLikelihoodBinary); .ot: its own
// writeData.
bool write_tree(const octomap::OcTree& tree, bool full, std::ostream& out) {
  std::optional<MaxLikelihoodBinary> binary;
  if (!full) binary.emplace(tree);
  out << (full ? "# Octomap OcTree file" : "# Octomap OcTree binary file") << "\n" << kWrittenByLine
      << "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n";
  out << "id " << tree.getTreeType() << std::endl;
  out << "size " << (full ? tree.size() : binary->size()) << std::endl;
  out << "res " << tree.getResolution() << std::endl;
  out << "data" << std::endl;
  if (full)
    tree.writeData(out);
  else
    binary->write(out);
  return out.good();
}

}  // namespace

void OctomapExportOptions::validate() const {
  require_parameter(occupancy_threshold > 0 && occupancy_threshold < 1, "occupancy_threshold", occupancy_threshold,
                    "in (0, 1)");
  require_parameter(unknown_band_probability >= 0 && unknown_band_probability < 0.5, "unknown_band_probability",
                    unknown_band_probability, "in [0, 0.5)");
  require_parameter(memory_cap_bytes > 0, "memory_cap_bytes", static_cast<double>(memory_cap_bytes), "> 0");
  require_parameter(free_leaves == FreeLeafRule::crossed || free_leaves == FreeLeafRule::wholly_free, "free_leaves",
                    static_cast<double>(free_leaves), "crossed (0) or wholly_free (1)");
}

std::unique_ptr<octomap::OcTree> make_octree(const ColumnGrid& grid, double resolution_m,
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

OctomapExportReport add_to_octree(octomap::OcTree& tree, const ColumnGrid& grid,
                                  const Eigen::Isometry3d& pose_given, const OctomapExportOptions& options) {
  const auto start = SteadyClock::now();
  options.validate();
  const Eigen::Isometry3d world_from_sensor = rigid_pose(pose_given);
  const GridGeometry& geometry = grid.geometry();
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

  const float band = static_cast<float>(logit(0.5 + options.unknown_band_probability));
  OctomapExportReport report;
  {  // The marks (~10^6 leaves at 6 mm) are freed before the pruning frees ~10^7 small nodes: a large block
     // freed after those makes glibc's malloc consolidate them all first (0.5 s, deaf to Ctrl-C).
    const PatchCover cover(tree, world_from_sensor.translation(), key_lo, key_hi, kPieceFraction * resolution,
                           curvature_pad_m(geometry, far_m));
    const LeafMarks marks = LeafMarker(grid, world_from_sensor, band, options.free_leaves, cover).mark();
    const auto write = [&](const octomap::OcTreeKey& key, float log_odds) {
      const octomap::OcTreeNode* node = tree.updateNode(key, log_odds, true);
      (tree.isNodeOccupied(node) ? report.occupied_written : report.free_written) += 1;
    };
    marks.for_each_occupied(write);
    write_free_leaves(tree, grid, world_from_sensor, far_m, key_lo, key_hi, band, options.free_leaves, marks, write,
                      report);
  }
  // Lazy insertion leaves inner nodes stale and every leaf expanded: refresh the inner nodes, then merge
  // children of equal value (uniform free space at the clamp) as OctoMap's own insertion does.
  update_inner_occupancy_and_prune(tree);
  report.seconds = seconds_since(start);
  return report;
}

void update_inner_occupancy_and_prune(octomap::OcTree& tree) {
  PollingTreeFinish finish(tree);
  finish.update_inner_occupancy();
  finish.prune();
}

std::unique_ptr<octomap::OcTree> to_octree(const ColumnGrid& grid, const Eigen::Isometry3d& world_from_sensor,
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

bool is_octomap_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string first_line, second_line;
  return std::getline(in, first_line) && first_line.rfind("# Octomap OcTree", 0) == 0 &&
         std::getline(in, second_line) && second_line == kWrittenByLine;
}

void write_octree(const octomap::OcTree& tree, const std::string& path) {
  require_octomap_output_path(path);
  const bool full = std::filesystem::path(path).extension() == ".ot";
  write_file_atomically(path, "OctoMap file", [&](std::ostream& out) {
    return write_tree(tree, full, out);
  });
}

}  // namespace occ_improve
