#pragma once
// Export of the spherical grid to OctoMap (the only part of occ_improve that includes OctoMap).
//
// Conversion rule, per OcTree leaf (a cube at the tree's resolution), from the spherical voxels it covers.
// A voxel is occupied when its log-odds is positive and outside the unknown band, free when negative and
// outside it, unknown otherwise (never touched, inside the band, or outside the grid's field of view or
// depth range).
//  - occupied: an occupied voxel reaches into the leaf. The leaf takes the largest log-odds of the occupied
//    voxels reaching it. So a surface thinner than the leaf (the kinect_v1 presets' occupied shell is a few
//    millimetres deep) leaves no hole, at any resolution.
//  - free (FreeLeafRule::crossed, the default): free space crosses the leaf, as OctoMap calls a leaf free
//    that a ray crosses. A leaf no free-space boundary reaches is free when the voxel holding its centre is;
//    one that a boundary reaches, when its centre or one of its 8 corners lies in a free voxel and no
//    column's surface voxel (its return) reaches it, as OctoMap never frees a leaf holding an endpoint. It
//    takes the log-odds of the voxel holding its centre, or where that is not free the largest (least
//    certain) of its free corners'.
//    (FreeLeafRule::wholly_free: the leaf lies wholly in free space; it takes the log-odds of its centre.)
//  - unknown (absent from the tree) otherwise: no free space found in the leaf, and no occupied voxel.
// The test is conservative, with a bound: each run of occupied voxels, and each face between free and
// non-free space (where a column's free run starts or ends, or two neighbouring columns differ), is cut
// into pieces no longer than a quarter leaf (or one column wide where a column is wider), and a leaf
// counts as reached when it meets a piece's axis-aligned bounding box. A pinhole voxel is the convex hull
// of its corners; a spherical voxel's curved faces are covered by padding the box. So no leaf holding
// occupied space is missed, and under wholly_free no leaf holding anything but free space is written
// free; a leaf is called occupied, or not wholly free, when such a voxel or face passes within that piece
// size of it but not through it. Under crossed a leaf a boundary passes is sampled at its centre and
// corners: free space crossing it between those points (a sliver) leaves it unknown. Compared with OctoMap's own insertPointCloud of the same frame, nearly every leaf it
// calls occupied is occupied in the export (tests/octomap/test_export_real.cpp); the export has more
// occupied leaves where the sensor model's occupied shell is deeper than a leaf (far range).
//
// Merge rule: several maps (different poses, or a map added to a tree that already holds data) merge by
// ADDING log-odds and then clamping to the tree's clamping thresholds (OcTree::updateNode). Maps taken
// from different poses are independent measurements of the same space, and adding log-odds is exactly
// the Bayesian fusion of independent evidence (eq. 2, OctoMap's own rule for every ray it inserts);
// clamping keeps the result able to change its mind, as in the grid. (Taking the max would make one
// confident but wrong view override every other one.) Adding the same map twice counts it twice.
#include "occ_improve/grid/grid.hpp"

#include <Eigen/Geometry>
#include <octomap/OcTree.h>

#include <cstddef>
#include <memory>
#include <string>

namespace occ_improve {

/// Which leaves the export writes free (the conversion rule above).
enum class FreeLeafRule {
  crossed,     ///< free space crosses the leaf (centre or a corner in a free voxel): OctoMap's own rule
  wholly_free  ///< the leaf lies wholly in free space: no unknown space is ever written free
};

struct OctomapExportOptions {
  /// P at or above which OctoMap calls a voxel occupied (OcTree::setOccupancyThres). 0.5: a voxel is
  /// occupied when the evidence leans that way at all, as the grid's own P does.
  double occupancy_threshold = 0.5;
  /// Voxels with |P - 0.5| below this are left unknown: the OPDF decays to exactly 1/2 behind a
  /// measurement, and a voxel with P = 0.5 + 1e-4 carries no information worth turning into "occupied".
  double unknown_band_probability = 0.01;
  /// crossed: as OctoMap's insertPointCloud marks free every leaf a ray crosses (at 10 cm, wholly_free
  /// leaves 60-90 % of that free space unknown). wholly_free: a leaf with some unknown space stays unknown.
  FreeLeafRule free_leaves = FreeLeafRule::crossed;
  /// Refuse an export whose estimated OcTree would need more memory than this (ResourceLimit).
  std::size_t memory_cap_bytes = std::size_t{2} << 30;

  void validate() const;  ///< InvalidParameter naming the field
};

struct OctomapExportReport {
  std::size_t leaves_examined = 0;  ///< OcTree leaf keys in the frustum's bounding box
  std::size_t occupied_written = 0;  ///< leaves written that the tree calls occupied afterwards
  std::size_t free_written = 0;      ///< leaves written that the tree calls free afterwards
  std::size_t left_unknown = 0;  ///< leaves whose centre is in the field of view, left out (unknown space, no occupied voxel)
  double seconds = 0;
};

/// An empty OcTree at `resolution_m` with the grid's clamping thresholds (exact-mode grids: probabilities
/// 0 and 1, i.e. log-odds -inf/+inf, no clamping, as eq. 2) and the occupancy threshold.
/// Throws InvalidParameter for resolution_m <= 0 or non-finite.
std::unique_ptr<octomap::OcTree> make_octree(const ColumnGrid& grid, double resolution_m,
                                             const OctomapExportOptions& options = {});

/// Adds `grid`, observed from `world_from_sensor`, to `tree` by the merge rule above, at the tree's
/// resolution; inner nodes are updated and equal children pruned before returning (as insertPointCloud
/// leaves its tree). A pose whose 3x3 part lies within 1e-3 (Frobenius) of a rotation (poses written with
/// 7-8 digits) is taken as that rotation. Throws InvalidParameter for a pose that is not a finite rigid
/// transform so (scaling, shear, reflection) or a frustum outside the tree's addressable range, ResourceLimit when the
/// estimated memory exceeds options.memory_cap_bytes. The tree is unchanged when it throws,
/// except for Cancelled (cancel.hpp): a stop request leaves it partly updated, for the caller to discard.
OctomapExportReport add_to_octree(octomap::OcTree& tree, const ColumnGrid& grid,
                                  const Eigen::Isometry3d& world_from_sensor,
                                  const OctomapExportOptions& options = {});

/// OctoMap's own `tree.updateInnerOccupancy(); tree.prune();`, node for node and with the same result,
/// but obeying a stop request (cancel.hpp): on a tree of 10^7 leaves written lazily (updateNode with
/// lazy_eval, as add_to_octree writes them) OctoMap's calls take about a second deaf to Ctrl-C. Throws
/// Cancelled, leaving the tree partly updated, for the caller to discard. add_to_octree ends with it.
void update_inner_occupancy_and_prune(octomap::OcTree& tree);

/// make_octree + add_to_octree.
std::unique_ptr<octomap::OcTree> to_octree(const ColumnGrid& grid, const Eigen::Isometry3d& world_from_sensor,
                                           double resolution_m, const OctomapExportOptions& options = {},
                                           OctomapExportReport* report = nullptr);

/// Writes `tree` as OctoMap's own writers do, chosen by extension: ".bt" (maximum likelihood: the bytes of
/// writeBinary(), whose leaves are each occupied or free and whose children of one state are merged) or
/// ".ot" (full log-odds, write()). The tree is not modified (writeBinary() would threshold and prune it). The file is written beside `path` and renamed into place: a failed write leaves no
/// half-written file. Throws InvalidParameter for another extension, IoError when it cannot write.
void write_octree(const octomap::OcTree& tree, const std::string& path);

/// Whether `path` is a tree write_octree wrote: OctoMap's first line ("# Octomap OcTree ...") and then
/// "# written by occ_improve" (a comment every OctoMap reader skips). What occ_to_octomap checks before it
/// replaces a file with -o: a tree from octomap_server or elsewhere is replaced only with -overwrite.
bool is_octomap_file(const std::string& path);

/// The extension check of write_octree alone, for tools to fail before any work.
void require_octomap_output_path(const std::string& path);

}  // namespace occ_improve
