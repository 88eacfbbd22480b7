#pragma once
// The depth binning of a grid (CONVENTIONS 2b): how a column's depth coordinate (range or z, the angular
// binning's choice) falls into bins, as an open interface. A binning gives only its bins' edges and centres
// over [depth_min_m, depth_max_m); the kernels use them through DepthAxis, whose lookups do not know the
// kind (a bucket table over the range, then an exact fix-up against the stored centres or edges).
//
// A new depth binning is one file: a class derived from DepthBinning and a line in the registry
// (depth_binning.cpp), or register_depth_binning() from outside the library. Its parameters are GeometryParams
// fields (the map file stores them all with the binning's tag).
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace occ_improve {

struct GeometryParams;

class DepthBinning {
public:
  /// The built-in binnings' tags (GeometryParams::depth_binning).
  static constexpr const char* uniform = "uniform";              ///< uniform in depth (the paper: [0, 5 m))
  static constexpr const char* inverse_depth = "inverse_depth";  ///< uniform in 1/depth, depth_min_m > 0

  virtual ~DepthBinning() = default;
  /// The name GeometryParams and the map file give this binning.
  virtual const char* tag() const = 0;
  /// The `bins` bins of [min_m, max_m): bins + 1 strictly increasing edges from min_m to max_m (exactly) and
  /// each bin's centre, strictly inside it. Bin 0 is the nearest. DepthAxis checks all of this.
  virtual void bins(double min_m, double max_m, int bins, std::vector<double>& edges,
                    std::vector<double>& centres) const = 0;
};

/// Builds a depth binning from the geometry's fields; validates the fields it uses (InvalidParameter naming one).
using DepthBinningFactory = std::function<std::shared_ptr<const DepthBinning>(const GeometryParams&)>;

/// Makes `tag` name a depth binning (replacing an earlier registration of the same tag). The built-ins are
/// registered from the start.
void register_depth_binning(const std::string& tag, DepthBinningFactory factory);
/// The binning GeometryParams::depth_binning names; InvalidParameter naming depth_binning and the registered
/// tags when none is registered under it.
std::shared_ptr<const DepthBinning> make_depth_binning(const GeometryParams& params);
bool is_registered_depth_binning(const std::string& tag);
std::vector<std::string> registered_depth_binnings();

/// A column's depth bins, from any depth binning. Bin 0 is the nearest.
class DepthAxis {
public:
  DepthAxis() = default;
  /// The bins `binning` gives [min_m, max_m); InvalidParameter when they break DepthBinning::bins' promises.
  DepthAxis(const DepthBinning& binning, double min_m, double max_m, int bins);
  /// The same for the binning registered under `tag` (validating min_m, max_m and bins as GeometryParams does).
  DepthAxis(const std::string& tag, double min_m, double max_m, int bins);
  int bins() const { return bins_; }
  /// The binning's tag.
  const std::string& binning() const { return binning_; }
  double min() const { return min_; }
  double max() const { return max_; }
  double centre(int b) const { return centres_[static_cast<std::size_t>(b)]; }
  double lower(int b) const { return edges_[static_cast<std::size_t>(b)]; }
  double upper(int b) const { return edges_[static_cast<std::size_t>(b) + 1]; }
  const std::vector<double>& centres() const { return centres_; }
  /// Bin containing rho (lower(b) <= rho < upper(b)): -1 below min (or NaN), bins() at or beyond max.
  int bin(double rho) const;
  /// Index of the first bin whose centre is strictly greater than rho, in [0, bins()]. Inline: the
  /// insertion calls it several times per (measurement, column) pair. The bucket of rho gives the first
  /// candidate in O(1) (buckets a fraction of the narrowest bin where the table's size allows), then
  /// the walk against the stored centres makes the result exact whatever the bucket's rounding. Buckets
  /// are finer than the bins, so the walk rarely takes a step: no mispredicted branch per call.
  int first_centre_above(double rho) const {
    const double k = (rho - min_) * buckets_per_m_;
    int b = !(k >= 0) ? 0 : (k >= buckets_ ? bins_ : first_above_[static_cast<std::size_t>(static_cast<int>(k))]);
    const double* centres = padded_centres_.data();
    b += centres[b] <= rho;  // the one centre a bucket mostly holds, without a branch (NaN: false at bins())
    while (b > 0 && centres[b - 1] > rho) --b;  // rounding at a bucket's start
    while (centres[b] <= rho) ++b;              // buckets holding several centres
    return b;
  }
  /// Width of the bin containing rho (the nearest or farthest bin outside the range).
  double width_at(double rho) const;

private:
  std::string binning_;
  double min_ = 0, max_ = 0, buckets_per_m_ = 0;
  int bins_ = 0, buckets_ = 0;
  std::vector<double> centres_, edges_;
  std::vector<double> padded_centres_;  ///< centres_ and a NaN, which compares false with every rho
  std::vector<int> first_above_;        ///< per bucket: the first bin whose centre is above the bucket's start
};

}  // namespace occ_improve
