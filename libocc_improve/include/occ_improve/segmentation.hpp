#pragma once
// Segmentation from the improvement map (the paper's closing remark: "sharp discontinuities are
// outlined by a region of negative improvement"). Per ray (column) of the spherical grid:
//  1. rays with a surface (known, occupied, inside the depth range) are valid; valid rays whose
//     improvement lies below `contour_improvement_below` are contour rays;
//  2. optionally the dominant plane (a table, a floor) is found by RANSAC over the surface points and
//     becomes one segment of its own, as PCL's organized segmentation leaves its dominant plane out;
//  3. 4-connected regions of the remaining valid, non-contour rays are segments; contours and no-data
//     holes separate them;
//  4. contour rays and regions smaller than `min_segment_columns` are attached, wave by wave from the
//     segments outwards, to the 4-neighbouring segment closest in depth, so every valid ray is labelled
//     (a leftover region with no segment around it becomes a segment of its own).
#include "occ_improve/geometry.hpp"
#include "occ_improve/improvement.hpp"
#include "occ_improve/presets.hpp"
#include "occ_improve/render.hpp"
#include "occ_improve/surface.hpp"

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
  std::size_t plane_min_columns = 3000;   ///< a smaller best plane is not removed
  int plane_ransac_iterations = 200;
  std::uint32_t plane_seed = 1;           ///< RANSAC is deterministic for a given seed

  /// Throws InvalidParameter naming the first bad field.
  void validate() const;
};

/// Defaults for a preset: the improvement's scale depends on the noise model (kinect_v1_paper's
/// constant 4.7 cm sigma gives a weaker, wider negative band than kinect_v1's range-dependent one).
SegmentationParams segmentation_defaults(const SensorPreset& preset);

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
  std::vector<Segment> segments;      ///< segments[l - 1] has label l, largest first
  std::size_t valid_columns = 0, contour_columns = 0, attached_columns = 0, plane_columns = 0;
};

/// Throws InvalidInput when surface or improvement do not match the geometry, InvalidParameter for
/// bad params. A surface with no valid ray gives no segments (not an error).
Segmentation segment_improvement(const SphericalGeometry& geometry, const SurfaceMap& surface,
                                 const ImprovementMap& improvement, const SegmentationParams& params = {});

/// A label's colour: a fixed hash, so a label keeps its colour; black for 0 (unlabelled).
std::array<std::uint8_t, 3> segment_colour(std::uint32_t label);
/// RGB: segment_colour of each ray's label.
Image render_segmentation(const Segmentation& segmentation);
/// Grey: contour rays white, other valid rays mid grey, no surface black.
Image render_contours(const Segmentation& segmentation);

}  // namespace occ_improve
