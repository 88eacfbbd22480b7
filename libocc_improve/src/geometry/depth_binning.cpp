#include "occ_improve/geometry/depth_binning.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/geometry/inverse_depth_binning.hpp"
#include "occ_improve/geometry/uniform_depth_binning.hpp"
#include "tag_registry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace occ_improve {
namespace {

// The built-ins from the start; register_depth_binning() adds to it.
detail::TagRegistry<DepthBinning>& registry() {
  static detail::TagRegistry<DepthBinning> r(
      "depth_binning", "depth binning",
      {{DepthBinning::uniform, [](const GeometryParams&) { return std::make_shared<UniformDepthBinning>(); }},
       {DepthBinning::inverse_depth,
        [](const GeometryParams& p) { return std::make_shared<InverseDepthBinning>(p); }}});
  return r;
}

// A binning's bins as DepthBinning::bins promises them; InvalidParameter naming the binning otherwise.
void check_bins(const std::string& tag, double min_m, double max_m, int bins, const std::vector<double>& edges,
                const std::vector<double>& centres) {
  const auto fail = [&](const std::string& problem) {
    throw InvalidParameter("depth_binning '" + tag + "': " + problem);
  };
  if (edges.size() != static_cast<std::size_t>(bins) + 1 || centres.size() != static_cast<std::size_t>(bins))
    fail("gave " + std::to_string(edges.size()) + " edges and " + std::to_string(centres.size()) +
         " centres for " + std::to_string(bins) + " bins");
  if (edges.front() != min_m || edges.back() != max_m) fail("edges do not run from depth_min_m to depth_max_m");
  for (int b = 0; b < bins; ++b) {
    const double lo = edges[static_cast<std::size_t>(b)], hi = edges[static_cast<std::size_t>(b) + 1];
    const double c = centres[static_cast<std::size_t>(b)];
    if (!(lo < c && c < hi)) fail("bin " + std::to_string(b) + " does not hold its centre strictly inside increasing edges");
  }
}

// Buckets per width of the narrowest bin; beyond kMaxBucketsPerBin per bin on average the table would
// outgrow the bins (inverse depth over [0.5, 8 m]: the narrowest bin is 1/16 of the mean), and the walk
// takes a step more often instead.
constexpr double kBucketsPerNarrowestBin = 4, kMaxBucketsPerBin = 16;

}  // namespace

void register_depth_binning(const std::string& tag, DepthBinningFactory factory) {
  registry().add(tag, std::move(factory));
}

std::vector<std::string> registered_depth_binnings() { return registry().tags(); }

bool is_registered_depth_binning(const std::string& tag) { return registry().has(tag); }

std::shared_ptr<const DepthBinning> make_depth_binning(const GeometryParams& params) {
  return registry().make(params.depth_binning, params);
}

DepthAxis::DepthAxis(const DepthBinning& binning, double min_m, double max_m, int bins)
    : binning_(binning.tag()), min_(min_m), max_(max_m), bins_(bins) {
  binning.bins(min_m, max_m, bins, edges_, centres_);
  check_bins(binning_, min_m, max_m, bins, edges_, centres_);
  padded_centres_ = centres_;
  padded_centres_.push_back(std::numeric_limits<double>::quiet_NaN());
  // A bucket no wider than the narrowest bin holds at most one centre beyond its first candidate; a
  // fraction of it, mostly none.
  double narrowest = max_m - min_m;
  for (int b = 0; b < bins; ++b) narrowest = std::min(narrowest, upper(b) - lower(b));
  buckets_ = static_cast<int>(std::clamp(std::ceil(kBucketsPerNarrowestBin * (max_m - min_m) / narrowest), 1.0,
                                         kMaxBucketsPerBin * bins));
  buckets_per_m_ = buckets_ / (max_m - min_m);
  first_above_.resize(static_cast<std::size_t>(buckets_));
  int b = 0;
  for (int k = 0; k < buckets_; ++k) {
    const double start = min_m + k / buckets_per_m_;
    while (b < bins && centre(b) <= start) ++b;
    first_above_[static_cast<std::size_t>(k)] = b;
  }
}

namespace {
GeometryParams depth_fields(const std::string& tag, double min_m, double max_m, int bins) {
  GeometryParams p;
  p.depth_binning = tag;
  p.depth_min_m = min_m;
  p.depth_max_m = max_m;
  p.depth_bins = bins;
  p.validate();  // the angular fields keep their (valid) defaults
  return p;
}
}  // namespace

DepthAxis::DepthAxis(const std::string& tag, double min_m, double max_m, int bins)
    : DepthAxis(*make_depth_binning(depth_fields(tag, min_m, max_m, bins)), min_m, max_m, bins) {}

int DepthAxis::bin(double rho) const {
  if (!(rho >= min_)) return -1;
  if (rho >= max_) return bins_;
  // centre(b - 1) <= rho < centre(b), and each centre lies inside its bin: rho is in bin b - 1 or b.
  const int b = first_centre_above(rho);
  return b < bins_ && rho >= lower(b) ? b : b - 1;
}

double DepthAxis::width_at(double rho) const {
  const int b = std::clamp(bin(rho), 0, bins_ - 1);
  return upper(b) - lower(b);
}

}  // namespace occ_improve
