#pragma once
// Segmentation from the improvement map (the paper's closing remark: "sharp discontinuities are
// outlined by a region of negative improvement"). Per ray (column) of the spherical grid:
//  1. rays with a surface (known, occupied, inside the depth range) are valid; valid rays whose
//     improvement lies below `contour_improvement_below` are contour rays;
//  2. optionally the dominant plane (a table, a floor) is found by RANSAC over the surface points and
//     becomes one segment of its own, as PCL's organized segmentation leaves its dominant plane out;
//  3. concave creases of the surface (where two surfaces meet in a valley without a depth step: a box
//     standing on or leaning against another) are cut as well: at each ray the surface points an arm's
//     length to either side, in 4 image directions, are compared with the ray's own; the ray is a crease
//     ray where the section bends by at least `crease_min_bend_deg` and bends away from the sensor
//     (concave, LCCP's convexity criterion on the surface map). A convex edge (the edge of one box) bends
//     towards the sensor and is not cut;
//  4. 4-connected regions of the remaining valid, non-contour, non-crease rays are segments; contours,
//     creases and no-data holes separate them;
//  5. contour and crease rays and regions smaller than `min_segment_columns` are attached, wave by wave from the
//     segments outwards, to the 4-neighbouring segment closest in depth, so every valid ray is labelled;
//     a leftover region smaller than that (an island between holes) joins the nearest segment within 4
//     columns across the holes whose depth lies within the plane band of its own, else it becomes a
//     segment of its own (docs/SEGMENTATION.md).
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/maps/image.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/maps/surface.hpp"

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occ_improve {

struct SegmentationParams {
  /// Valid rays with improvement below this are contour rays (must be < 0: the paper's negative band).
  float contour_improvement_below = -0.02f;
  /// Regions with fewer rays are not segments of their own but attached to a neighbouring segment.
  std::size_t min_segment_columns = 200;
  /// Dominant-plane removal (RANSAC over the surface points). On by default: the table or floor touches
  /// every object standing on it, and without removal they merge into one segment (docs/SEGMENTATION.md).
  bool remove_dominant_plane = true;
  double plane_distance_m = 0.01;         ///< inlier band half-width around the plane
  /// The band widens with range as the depth noise does: at least this x range^2 [1/m] (0: the same band
  /// at every range). segmentation_defaults sets 2.5 x the model's sigma_depth_per_m2: a floor or wall at 5 m
  /// (sigma 36 mm) fell out of a 6 mm band on most of its rays, a speckle of plane and non-plane rays.
  double plane_distance_per_m2 = 0.0;
  std::size_t plane_min_columns = 3000;   ///< a smaller best plane is not removed
  int plane_ransac_iterations = 200;
  std::uint32_t plane_seed = 1;           ///< RANSAC is deterministic for a given seed

  /// Concave creases cut segments too (step 3). Off: the improvement contours and the plane only.
  bool split_concave_creases = true;
  /// Arm length along the surface between a ray and the points it is compared with. A few centimetres:
  /// long against the Kinect's 1-3 mm depth noise and its quantisation steps at 1-1.5 m, short against the
  /// faces of table-top objects. Converted to pixels per ray from its depth.
  double crease_arm_m = 0.02;
  /// The arm grows with range as the depth noise does: it is at least this x range^2 [1/m] (up to
  /// crease_max_arm_px: beyond ~5 m for kinect_v1 the cap holds it), and crease_arm_m at every range where 0. segmentation_defaults sets 6 x the model's sigma_depth_per_m2:
  /// six sigma, about three of the Kinect's quantisation steps (2.9e-3 x range^2), as 2 cm is up to
  /// 1.5 m. A shorter arm on a far face measures the noise: at 3.5-4 m (sigma 17-23 mm, steps 3.5-4.6 cm)
  /// the 2 cm arm marked 54 % of person.pcd's back wall as crease (docs/SEGMENTATION.md).
  double crease_arm_per_m2 = 0.0;
  /// The surface points are averaged over a square reaching this share of the arm to each side first, so
  /// the sensor's depth quantisation (a staircase on slanted faces) does not read as a bend. A quarter (5 mm
  /// each way at the default arm, a few quantisation steps) leaves the crease itself sharp; half an arm
  /// rounds it off so far that creases between stacked boxes break up (measured, docs/SEGMENTATION.md).
  double crease_smoothing_share = 0.25;
  /// Minimum bend of the section (the angle between the two arms, 0 for a flat surface). Faces of boxes
  /// meet at 90 deg; a section across the crease at an angle or with the corner rounded by the smoothing
  /// sees less. Noise on a flat face bends the section by ~atan(sigma / arm) ~ 5 deg.
  double crease_min_bend_deg = 30.0;
  /// A section whose arm makes less than this angle with the line of sight is a depth step seen across
  /// (the near surface occludes the far one), not two faces meeting: skipped. A structured-light sensor
  /// returns little from faces seen within ~20 deg of grazing, so arms on faces it does see make more.
  double crease_min_view_angle_deg = 20.0;
  /// Beyond this range [m] the minimum view angle shrinks as crease_view_angle_range_m / range (0: the
  /// same angle at every range). A floor or wall seen from a fixed height turns grazing as 1 / range (from
  /// 1.2 m up, a floor beyond 3.3 m is seen within 20 deg), and there depth noise tips arms under a fixed
  /// angle, so a box on a floor at 3 m joined it. segmentation_defaults sets 1.5 m (docs/SEGMENTATION.md).
  double crease_view_angle_range_m = 0.0;
  int crease_max_arm_px = 24;  ///< cap on the arm in pixels (near surfaces), bounding the cost per ray
  /// Threads for the back-projection and the crease scan, as InsertionOptions::threads: 0 = every
  /// hardware thread, 1 = the calling thread only; in [0, 1024]. Any value gives the same segmentation.
  int threads = 0;

  /// Throws InvalidParameter naming the first bad field.
  void validate() const;
};

/// Defaults for a preset: the improvement's scale depends on the noise model (a constant sigma_rho, as
/// kinect_v1_paper's 4.7 cm, gives a weaker, wider negative band than kinect_v1's range-dependent one) and
/// the plane band on the binning (pixel-native). Only the preset's geometry and model are read.
SegmentationParams segmentation_defaults(const SensorPreset& preset);
/// The same from a grid's geometry and model (a Mapper's, or a loaded map's).
SegmentationParams segmentation_defaults(const GeometryParams& geometry, const SensorModelParams& model);

struct Segment {
  std::uint32_t label = 0;       ///< 1-based, as in Segmentation::label
  std::size_t columns = 0;       ///< rays in the segment
  Eigen::Vector3d centroid_m{0, 0, 0};  ///< mean surface point (sensor frame)
  double mean_depth_m = 0;
  bool plane = false;            ///< the removed dominant plane
};

struct Segmentation {
  int width = 0, height = 0;
  std::vector<std::uint32_t> label;   ///< per column; 0 = no segment (no valid surface)
  std::vector<std::uint8_t> contour;  ///< 1 on contour rays (improvement below the threshold)
  std::vector<std::uint8_t> crease;   ///< 1 on concave-crease rays (not contour rays)
  std::vector<Segment> segments;      ///< segments[l - 1] has label l, largest first
  std::size_t valid_columns = 0, contour_columns = 0, crease_columns = 0, attached_columns = 0, plane_columns = 0;
  ColumnShape shape() const {
    return ColumnShape::of_arrays(width, height, {label.size(), contour.size(), crease.size()});
  }
};

/// Throws InvalidInput when surface or improvement do not match the geometry, InvalidParameter for
/// bad params. A surface with no valid ray gives no segments (not an error).
Segmentation segment_improvement(const GridGeometry& geometry, const SurfaceMap& surface,
                                 const ImprovementMap& improvement, const SegmentationParams& params = {});

/// A label's colour: a fixed hash, so a label keeps its colour; black for 0 (unlabelled).
std::array<std::uint8_t, 3> segment_colour(std::uint32_t label);
/// RGB: segment_colour of each ray's label.
Image render_segmentation(const Segmentation& segmentation);
/// Grey: contour rays white, other valid rays mid grey, no surface black.
Image render_contours(const Segmentation& segmentation);

}  // namespace occ_improve
