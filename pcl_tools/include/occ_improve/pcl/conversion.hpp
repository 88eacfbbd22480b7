#pragma once
// PCL clouds -> core point spans, without copying; organized clouds <-> depth images and intrinsics.
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/intrinsics_fit.hpp"

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <limits>
#include <string>
#include <vector>

namespace occ_improve {

/// A view of a PCL cloud's xyz as a PointSpan (every PCL XYZ type starts with x, y, z floats).
template <typename PointT>
PointSpan span_of(const pcl::PointCloud<PointT>& cloud) {
  static_assert(sizeof(PointT) % sizeof(float) == 0, "point type size must be a whole number of floats");
  return {cloud.empty() ? nullptr : &cloud.points.front().x, cloud.size(), sizeof(PointT) / sizeof(float)};
}

/// How many points the insertion can use at all: finite and not at the origin (insert_points counts the
/// others as skipped_invalid).
std::size_t valid_point_count(PointSpan points);

/// Throws InvalidInput "'<name>' holds no valid point (...)" when valid_point_count(points) is 0. This
/// is the one rule by which every tool refuses an empty, all-NaN or all-zero frame (docs: README, Errors).
void require_valid_points(PointSpan points, const std::string& name);

/// Throws InvalidInput "'<name>': the points' median range is ... m, outside the grid's plausible depth range
/// [a, b] m: they look like millimetres (times 0.001 gives metres) (the <what>)<hint>" when another usual unit
/// would put the points inside `grid`'s range (point_unit_mistake, integrate/point_units.hpp). `what`:
/// "cloud" or "image" ("": no parenthesis); `hint`: what to do (": the tools read clouds in metres").
/// Mapper::insert takes any unit as metres (a cloud in millimetres maps "beyond the depth range"): a
/// program that reads clouds from users calls this first, as the tools do.
void require_points_in_metres(PointSpan points, const std::string& name, const GeometryParams& grid,
                              const std::string& what = "", const std::string& hint = "");

/// An organized width x height cloud from per-pixel points in row-major order, NaN where there is no
/// return (sample::SampleFrame::points(), depth_image_to_points()). Throws InvalidInput on a size mismatch.
pcl::PointCloud<pcl::PointXYZ> organized_cloud(const std::vector<Eigen::Vector3f>& points, int width, int height);

/// The other way: an organized cloud's z per pixel, row-major, 0 where it has no return (the depth image a
/// VirtualSensor takes as its scene). Throws InvalidInput for a cloud that is not organized.
std::vector<float> depth_of_organized(const pcl::PointCloud<pcl::PointXYZ>& cloud);

/// Pinhole intrinsics of an organized cloud from a pinhole camera, fitted by least squares to
/// u = fx x/z + cx and v = fy y/z + cy over its valid points (fit_intrinsics_checked), with the fit's
/// residual. Throws InvalidInput when the cloud is not organized, has fewer than 100 valid points, or fits
/// worse than max_rms_px (the message names the residual and -intrinsics); InvalidParameter for a
/// max_rms_px not finite or <= 0. The default is the tools' (a cloud from a pinhole camera fits to ~1e-4 px;
/// its default was infinity, which the check refuses: every call without it threw).
template <typename PointT>
IntrinsicsFit estimate_intrinsics_fit(const pcl::PointCloud<PointT>& cloud, double max_rms_px = kMaxIntrinsicsFitResidualPx);

/// The intrinsics alone, refusing a fit worse than kMaxIntrinsicsFitResidualPx.
template <typename PointT>
PinholeIntrinsics estimate_intrinsics(const pcl::PointCloud<PointT>& cloud);

}  // namespace occ_improve
