#pragma once
// The angular binning of a grid (CONVENTIONS 2, 2c; docs/CONVENTIONS.md section 2): how directions fall into
// columns, as an open interface. The kernels (insertion, surface, improvement, export) use a binning
// without knowing its kind: they ask it for a point's continuous angular position and depth coordinate
// (position), the columns a support overlaps and the column centres (its two axes, in its own angular
// unit), a column's points (point_at), and the unit its sensor sigmas are given in (unit). The angular
// term of eq. 1 is B = ((h - h_c)/sigma_h)^2 + ((v - v_c)/sigma_v)^2 in that unit: separable, so the
// insertion factors e^-B per axis and the improvement tabulates it per column offset and per row.
//
// A new binning is one file: a class derived from AngularBinning and a line in the registry
// (angular_binning.cpp), or register_angular_binning() from outside the library. Its parameters are
// GeometryParams fields (the map file stores them all with the binning's tag).
#include <Eigen/Core>
#include <algorithm>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace occ_improve {

struct GeometryParams;

/// Bins of one angular axis: uniform over [min, max), or around given centres (non-uniform). Bin 0 is at min.
class BinAxis {
public:
  BinAxis() = default;
  /// `bins` uniform bins over [min, max).
  BinAxis(double min, double max, int bins);
  /// Bins around given centres (strictly increasing, at least 2; the caller validates): edges halfway
  /// between neighbours, the outer ones half the neighbouring gap beyond the first and last centre.
  static BinAxis from_centres(std::vector<double> centres);
  int bins() const { return bins_; }
  double min() const { return min_; }
  double max() const { return max_; }
  bool uniform() const { return uniform_; }
  /// The bin width of a uniform axis (the mean width of a non-uniform one).
  double width() const { return width_; }
  double width(int i) const { return lower(i + 1) - lower(i); }
  /// Bin containing `value`, or -1 when outside [min, max). Inline (with overlapping): the insertion
  /// calls both for every point.
  int bin(double value) const {
    if (!(value >= min_ && value < max_)) return -1;
    if (!uniform_) return bin_from_edges(value);
    const int i = static_cast<int>((value - min_) * inv_width_);
    return std::min(i, bins_ - 1);  // guards rounding right below max
  }
  double centre(int i) const { return centres_[static_cast<std::size_t>(i)]; }
  /// Lower edge of bin i; lower(bins()) is the axis' upper end.
  double lower(int i) const { return edges_[static_cast<std::size_t>(i)]; }
  /// centre(i + di) - centre(i); di times the width on a uniform axis (exactly, whatever i).
  double centre_offset(int i, int di) const { return uniform_ ? di * width_ : centre(i + di) - centre(i); }
  /// Bins whose extent overlaps [lo, hi], clipped to the axis; empty (first > last) when none.
  void overlapping(double lo, double hi, int& first, int& last) const {
    // The bins holding lo and hi (half-open), clipped.
    first = uniform_ ? floor_to_int((lo - min_) * inv_width_) : bin_from_edges(lo);
    last = uniform_ ? floor_to_int((hi - min_) * inv_width_) : bin_from_edges(hi);
    first = std::max(first, 0);
    last = std::min(last, bins_ - 1);
  }

private:
  // static_cast<int>(std::floor(x)) without the libm call floor is on baseline x86-64.
  static int floor_to_int(double x) {
    const int i = static_cast<int>(x);
    return i - (x < i);
  }
  int bin_from_edges(double value) const;  // the bin holding value: -1 below min, bins() at or beyond max

  double min_ = 0, max_ = 1, width_ = 1, inv_width_ = 1;
  int bins_ = 0;
  bool uniform_ = true;
  std::vector<double> centres_, edges_;
};

/// Deprecated name (0.2) of BinAxis: axes may be non-uniform since the open binnings.
using UniformAxis = BinAxis;

/// The unit of a binning's angular positions; the sensor model keeps its angular sigmas per unit
/// (sigma_azimuth_rad / sigma_elevation_rad, sigma_u_px / sigma_v_px).
enum class AngularUnit { radians, pixels };

class AngularBinning {
public:
  /// The built-in binnings' tags (GeometryParams::angular_binning).
  static constexpr const char* spherical = "spherical";
  static constexpr const char* pinhole = "pinhole";
  static constexpr const char* lidar_rings = "lidar_rings";

  virtual ~AngularBinning() = default;
  /// The name GeometryParams and the map file give this binning.
  virtual const char* tag() const = 0;
  virtual AngularUnit unit() const = 0;
  /// Horizontal (columns of a row) and vertical (rows) axes, in unit(). The horizontal axis is uniform
  /// (the improvement's row loop relies on it); the vertical one may not be.
  const BinAxis& horizontal() const { return horizontal_; }
  const BinAxis& vertical() const { return vertical_; }
  /// Continuous angular position of a point (sensor frame) and its depth coordinate (range or z); false
  /// where the binning gives it no position (behind a camera). Whether it is inside the axes is the caller's.
  virtual bool position(double x, double y, double z, double& h, double& v, double& depth) const = 0;
  /// Unit direction at a continuous angular position.
  virtual Eigen::Vector3d direction_at(double h, double v) const = 0;
  /// Point at depth coordinate `depth` at a continuous angular position.
  virtual Eigen::Vector3d point_at(double h, double v, double depth) const = 0;
  /// The widest angle across a column's diagonal [rad] when the depth coordinate is the range (the depth
  /// bins' faces are spheres); 0 when it is z (planes). The OctoMap export pads its boxes by it.
  virtual double curvature_angle_rad() const = 0;
  /// True when column (a, e) is pixel (a, e) of GeometryParams::camera (every column observable).
  virtual bool columns_are_camera_pixels() const { return false; }

protected:
  AngularBinning(BinAxis horizontal, BinAxis vertical)
      : horizontal_(std::move(horizontal)), vertical_(std::move(vertical)) {}

private:
  BinAxis horizontal_, vertical_;
};

/// binning == "pinhole": compares the tag (what `binning == AngularBinning::pinhole` meant before 0.2).
inline bool operator==(const AngularBinning& b, std::string_view tag) { return tag == b.tag(); }
inline bool operator!=(const AngularBinning& b, std::string_view tag) { return !(b == tag); }
inline std::ostream& operator<<(std::ostream& os, const AngularBinning& b) { return os << b.tag(); }

/// Builds a binning from the geometry's fields; validates the fields it uses (InvalidParameter naming one).
using AngularBinningFactory = std::function<std::shared_ptr<const AngularBinning>(const GeometryParams&)>;

/// Makes `tag` name a binning (replacing an earlier registration of the same tag). The built-ins are
/// registered from the start.
void register_angular_binning(const std::string& tag, AngularBinningFactory factory);
/// The binning GeometryParams::angular_binning names; InvalidParameter naming angular_binning and the
/// registered tags when none is registered under it.
std::shared_ptr<const AngularBinning> make_angular_binning(const GeometryParams& params);
bool is_registered_angular_binning(const std::string& tag);
std::vector<std::string> registered_angular_binnings();

}  // namespace occ_improve
