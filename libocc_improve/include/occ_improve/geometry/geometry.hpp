#pragma once
// Grid geometry (CONVENTIONS 1-2, 2b, 2c): an angular binning of directions into columns (rays) and a depth
// binning along each column (uniform, uniform in inverse depth, or one registered: depth_binning.hpp),
// behind one type. The kernels ask it
// only for a direction's continuous position (project), the columns a support overlaps (the binning's
// two axes, in its own angular unit), a column's centre (point) and, with the sensor model, the angular
// term in that unit. The binning is an open interface (angular_binning.hpp): a new one is a new file and
// a registration; insertion, surface, improvement and everything after them are unchanged.
//
// Built-in binnings (GeometryParams::angular_binning names one):
//  - "spherical" (the paper, CONVENTIONS 2): columns uniform in azimuth theta = atan2(x, z) and elevation
//    phi = atan2(y, hypot(x, z)), radians; the depth axis is the range rho = |p|.
//  - "pinhole" (pixel-native, CONVENTIONS 2c): column (u, v) is pixel (u, v) of a pinhole camera, positions in
//    pixels (u = fx x / z + cx, v = fy y / z + cy); the depth axis is z. z rather than the range
//    because the sensor measures and quantises z (a Kinect's disparity is per z), so a flat wall facing
//    the camera falls in one depth bin at every pixel instead of in rings of range bins.
//  - "lidar_rings" (a spinning LiDAR's range image): columns uniform azimuth steps, rows the rings at
//    their own elevations (row_elevations_rad, not evenly spaced), radians; the depth axis is the range.
// Frame: the sensor's optical frame (x right, y down, z forward). Units: metres; radians or pixels.
#include "occ_improve/geometry/angular_binning.hpp"
#include "occ_improve/geometry/depth_binning.hpp"

#include <Eigen/Core>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// A pinhole depth camera (pixels; u right, v down).
struct PinholeIntrinsics {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;
  void validate() const;
  bool operator==(const PinholeIntrinsics& o) const {
    return fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy && width == o.width && height == o.height;
  }
  bool operator!=(const PinholeIntrinsics& o) const { return !(*this == o); }
};

/// Same size and fx, fy, cx, cy within 0.05 px: one camera, up to the ~1e-4 px by which fitted or
/// file-rounded intrinsics of one sensor differ. Half a pixel (cx 319.5 against 320, both common) is not.
bool same_camera(const PinholeIntrinsics& a, const PinholeIntrinsics& b);
/// "fx=525.00 fy=525.00 cx=319.50 cy=239.50 640x480", for messages.
std::string camera_text(const PinholeIntrinsics& k);

/// The tag itself (to_string(AngularBinning) of 0.1, whose binnings were an enum).
inline const char* to_string(const std::string& binning_tag) { return binning_tag.c_str(); }

struct GeometryParams {
  /// The binning's registered tag: "spherical", "pinhole", "lidar_rings" (AngularBinning::spherical, ...)
  /// or one registered with register_angular_binning().
  std::string angular_binning = AngularBinning::spherical;
  /// pinhole: the camera whose pixels are the columns (required; its size must equal the bin counts).
  /// spherical: when set, columns whose centre direction falls outside this camera's image are not
  /// observable (CONVENTIONS 2c): they take no part in ranking, regions, stop signals or the filter.
  std::optional<PinholeIntrinsics> camera;
  /// Angular bin counts (columns per row and rows), for both binnings.
  int azimuth_bins = 640;
  int elevation_bins = 480;
  int depth_bins = 512;
  /// Angular range of the spherical binning, and the azimuth range of lidar_rings (unused by the pinhole
  /// binning, whose range is the image).
  double azimuth_min_rad = -0.497418836818384;  ///< -28.5 deg
  double azimuth_max_rad = 0.497418836818384;
  double elevation_min_rad = -0.375245789179833;  ///< -21.5 deg
  double elevation_max_rad = 0.375245789179833;
  /// lidar_rings: the elevation phi = atan2(y, hypot(x, z)) of each ring, rows top to bottom (strictly
  /// increasing: y points down, so the most upward ring comes first); elevation_bins rings. Others: empty.
  std::vector<double> row_elevations_rad;
  /// The depth binning's registered tag: "uniform" (the paper), "inverse_depth" (DepthBinning::uniform, ...)
  /// or one registered with register_depth_binning().
  std::string depth_binning = DepthBinning::uniform;
  double depth_min_m = 0.0;
  double depth_max_m = 5.0;

  /// Throws InvalidParameter naming the first bad field.
  void validate() const;
};

/// A point in spherical coordinates (CONVENTIONS 1).
struct SphericalPoint {
  double rho = 0;
  double azimuth = 0;
  double elevation = 0;
};

SphericalPoint to_spherical(double x, double y, double z);
Eigen::Vector3d from_spherical(const SphericalPoint& s);

using ColumnIndex = std::uint32_t;

/// InvalidParameter unless width and height are > 0 and every column of width x height has a ColumnIndex
/// (at most 2^32 - 1 columns), for functions given a grid's size rather than a grid.
void require_column_grid_size(int width, int height);

/// CONVENTIONS 1: a point is valid when every coordinate is finite and it is not the origin (no return).
inline bool is_valid_point(double x, double y, double z) {
  return std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && !(x == 0 && y == 0 && z == 0);
}

/// Where a point falls in the grid: continuous angular position (the binning's unit), the columns'
/// bins containing it, and its coordinate on the depth axis (range or z).
struct RayPosition {
  double horizontal = 0, vertical = 0;  ///< in the binning's unit: azimuth/elevation [rad] or u/v [px]
  int horizontal_bin = -1, vertical_bin = -1;
  double depth = 0;  ///< range [m] (spherical, lidar_rings) or z [m] (pinhole)
};

/// The whole grid's geometry: columns (rays) in rows like image pixels, each with depth bins.
/// Columns are numbered like image pixels: column = elevation_bin * azimuth_bins + azimuth_bin.
/// "azimuth"/"elevation" name the horizontal and vertical angular axes of either binning.
class GridGeometry {
public:
  explicit GridGeometry(const GeometryParams& params);
  const GeometryParams& params() const { return params_; }
  /// The angular binning; `binning() == AngularBinning::pinhole` compares its tag.
  const AngularBinning& binning() const { return *binning_; }
  /// Horizontal / vertical angular axes, in the binning's unit (radians, or pixels from -0.5).
  const BinAxis& azimuth() const { return binning_->horizontal(); }
  const BinAxis& elevation() const { return binning_->vertical(); }
  const DepthAxis& depth() const { return depth_; }
  /// Position of a point (sensor frame); false when its direction is outside the field of view
  /// (for the pinhole binning also z <= 0). The point must be finite and not the origin.
  bool project(double x, double y, double z, RayPosition& position) const;
  /// The column of a point (sensor frame): the one point-to-column rule of every caller. False for an
  /// invalid point (a coordinate not finite, or the origin) and outside the field of view.
  bool column_of(double x, double y, double z, ColumnIndex& column) const;
  /// Columns a camera can observe (every column, unless a grid whose columns are not the camera's pixels
  /// was given a camera).
  bool observable(ColumnIndex c) const { return observable_.empty() || observable_[c] != 0; }
  bool all_observable() const { return observable_.empty(); }
  std::size_t observable_count() const;
  int width() const { return azimuth().bins(); }    ///< columns per elevation row (image width)
  int height() const { return elevation().bins(); }  ///< elevation rows (image height)
  std::size_t column_count() const { return static_cast<std::size_t>(width()) * static_cast<std::size_t>(height()); }
  ColumnIndex column(int azimuth_bin, int elevation_bin) const {
    return static_cast<ColumnIndex>(elevation_bin) * static_cast<ColumnIndex>(width()) +
           static_cast<ColumnIndex>(azimuth_bin);
  }
  int azimuth_bin_of(ColumnIndex c) const { return static_cast<int>(c % static_cast<ColumnIndex>(width())); }
  int elevation_bin_of(ColumnIndex c) const { return static_cast<int>(c / static_cast<ColumnIndex>(width())); }
  /// Unit direction through the centre of a column.
  Eigen::Vector3d direction(int azimuth_bin, int elevation_bin) const;
  /// Unit direction at a continuous angular position (the binning's unit), e.g. a region's centroid.
  Eigen::Vector3d direction_at(double horizontal, double vertical) const;
  /// Point at coordinate `depth` of the depth axis (range, or z for the pinhole binning) on the ray
  /// through the centre of a column.
  Eigen::Vector3d point(int azimuth_bin, int elevation_bin, double depth) const {
    return point_at(azimuth().centre(azimuth_bin), elevation().centre(elevation_bin), depth);
  }
  /// The same at a continuous angular position.
  Eigen::Vector3d point_at(double horizontal, double vertical, double depth) const {
    return binning_->point_at(horizontal, vertical, depth);
  }
  bool operator==(const GridGeometry& other) const;

private:
  GeometryParams params_;
  std::shared_ptr<const AngularBinning> binning_;
  DepthAxis depth_;
  std::vector<std::uint8_t> observable_;  ///< empty: every column observable
};

/// Deprecated name (0.1) of GridGeometry, kept for one release (CHANGELOG.md): the default grid is pixel-native, not spherical.
using SphericalGeometry [[deprecated("renamed GridGeometry in 0.2")]] = GridGeometry;

}  // namespace occ_improve
