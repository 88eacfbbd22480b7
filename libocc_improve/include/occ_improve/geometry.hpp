#pragma once
// Spherical grid geometry (SPEC 1-2, 2b): angular binning in azimuth and elevation and depth binning
// (uniform or uniform in inverse depth), behind one type. Insertion and improvement only ask this type
// for bins, extents and centres, so another binning is added here without touching them.
//
// Frame: the sensor's optical frame (x right, y down, z forward). Units: metres and radians.
//   rho = |p|, azimuth theta = atan2(x, z), elevation phi = atan2(y, hypot(x, z)).
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occ_improve {

enum class DepthBinning {
  uniform,        ///< bins uniform in rho over [depth_min_m, depth_max_m) (the paper: [0, 5 m))
  inverse_depth,  ///< bins uniform in 1/rho between depth_min_m > 0 and depth_max_m (width grows as rho^2)
};

struct GeometryParams {
  int azimuth_bins = 640;
  int elevation_bins = 480;
  int depth_bins = 512;
  double azimuth_min_rad = -0.497418836818384;  ///< -28.5 deg
  double azimuth_max_rad = 0.497418836818384;
  double elevation_min_rad = -0.375245789179833;  ///< -21.5 deg
  double elevation_max_rad = 0.375245789179833;
  DepthBinning depth_binning = DepthBinning::uniform;
  double depth_min_m = 0.0;
  double depth_max_m = 5.0;

  /// Throws InvalidParameter naming the first bad field.
  void validate() const;
};

/// A point in spherical coordinates (SPEC 1).
struct SphericalPoint {
  double rho = 0;
  double azimuth = 0;
  double elevation = 0;
};

SphericalPoint to_spherical(double x, double y, double z);
Eigen::Vector3d from_spherical(const SphericalPoint& s);

/// Uniform bins over [min, max).
class UniformAxis {
public:
  UniformAxis() = default;
  UniformAxis(double min, double max, int bins);
  int bins() const { return bins_; }
  double min() const { return min_; }
  double max() const { return max_; }
  double width() const { return width_; }
  /// Bin containing `value`, or -1 when outside [min, max).
  int bin(double value) const;
  double centre(int i) const { return min_ + (i + 0.5) * width_; }
  double lower(int i) const { return min_ + i * width_; }
  /// Bins whose extent overlaps [lo, hi], clipped to the axis; empty (first > last) when none.
  void overlapping(double lo, double hi, int& first, int& last) const;

private:
  double min_ = 0, max_ = 1, width_ = 1, inv_width_ = 1;
  int bins_ = 1;
};

/// Depth bins, uniform in rho or in 1/rho. Bin 0 is the nearest.
class DepthAxis {
public:
  DepthAxis() = default;
  DepthAxis(DepthBinning binning, double min_m, double max_m, int bins);
  int bins() const { return bins_; }
  DepthBinning binning() const { return binning_; }
  double min() const { return min_; }
  double max() const { return max_; }
  double centre(int b) const { return centres_[static_cast<std::size_t>(b)]; }
  double lower(int b) const { return edges_[static_cast<std::size_t>(b)]; }
  double upper(int b) const { return edges_[static_cast<std::size_t>(b) + 1]; }
  const std::vector<double>& centres() const { return centres_; }
  /// Bin containing rho: -1 below min, bins() at or beyond max.
  int bin(double rho) const;
  /// Index of the first bin whose centre is strictly greater than rho, in [0, bins()]. Inline: the
  /// insertion calls it several times per (measurement, column) pair. The bin is guessed in closed form
  /// (linear in rho, or in 1/rho), then fixed up against the stored centres, so the result is exact.
  int first_centre_above(double rho) const {
    const double ci = binning_ == DepthBinning::uniform ? (rho - min_) * bins_per_unit_
                                                        : (rho > 0 ? (inverse_min_ - 1.0 / rho) * bins_per_unit_ : -1.0);
    // centre(b) > rho  <=>  b + 0.5 > ci; the cast floors because ci + 0.5 >= 0 there.
    int b = !(ci >= -0.5) ? 0 : (ci >= bins_ ? bins_ : static_cast<int>(ci + 0.5));
    const double* centres = centres_.data();
    while (b > 0 && centres[b - 1] > rho) --b;
    while (b < bins_ && centres[b] <= rho) ++b;
    return b;
  }
  /// Width of the bin containing rho (the nearest or farthest bin outside the range).
  double width_at(double rho) const;

private:
  double continuous_index(double rho) const;  // bin coordinate: bin b spans [b, b+1)
  DepthBinning binning_ = DepthBinning::uniform;
  double min_ = 0, max_ = 1;
  double inverse_min_ = 0, bins_per_unit_ = 1;  ///< bins per metre (uniform) or per 1/m (inverse depth)
  int bins_ = 1;
  std::vector<double> centres_, edges_;
};

using ColumnIndex = std::uint32_t;

/// The whole grid's geometry: azimuth x elevation columns (rays), each with depth bins.
/// Columns are numbered like image pixels: column = elevation_bin * azimuth_bins + azimuth_bin.
class SphericalGeometry {
public:
  explicit SphericalGeometry(const GeometryParams& params);
  const GeometryParams& params() const { return params_; }
  const UniformAxis& azimuth() const { return azimuth_; }
  const UniformAxis& elevation() const { return elevation_; }
  const DepthAxis& depth() const { return depth_; }
  int width() const { return azimuth_.bins(); }    ///< columns per elevation row (image width)
  int height() const { return elevation_.bins(); }  ///< elevation rows (image height)
  std::size_t column_count() const { return static_cast<std::size_t>(width()) * height(); }
  ColumnIndex column(int azimuth_bin, int elevation_bin) const {
    return static_cast<ColumnIndex>(elevation_bin) * static_cast<ColumnIndex>(width()) +
           static_cast<ColumnIndex>(azimuth_bin);
  }
  int azimuth_bin_of(ColumnIndex c) const { return static_cast<int>(c % static_cast<ColumnIndex>(width())); }
  int elevation_bin_of(ColumnIndex c) const { return static_cast<int>(c / static_cast<ColumnIndex>(width())); }
  /// Column containing the direction, false when outside the angular range.
  bool locate(double azimuth, double elevation, int& azimuth_bin, int& elevation_bin) const;
  /// Unit direction through the centre of a column.
  Eigen::Vector3d direction(int azimuth_bin, int elevation_bin) const;
  /// Point at depth rho on the ray through the centre of a column.
  Eigen::Vector3d point(int azimuth_bin, int elevation_bin, double rho) const {
    return direction(azimuth_bin, elevation_bin) * rho;
  }
  bool operator==(const SphericalGeometry& other) const;

private:
  GeometryParams params_;
  UniformAxis azimuth_, elevation_;
  DepthAxis depth_;
};

}  // namespace occ_improve
