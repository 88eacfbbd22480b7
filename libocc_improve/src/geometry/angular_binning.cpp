#include "occ_improve/geometry/angular_binning.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/geometry.hpp"
#include "occ_improve/geometry/lidar_rings_binning.hpp"
#include "occ_improve/geometry/pinhole_binning.hpp"
#include "occ_improve/geometry/spherical_binning.hpp"
#include "tag_registry.hpp"

#include <algorithm>
#include <cmath>

namespace occ_improve {

BinAxis::BinAxis(double min, double max, int bins)
    : min_(min), max_(max), width_((max - min) / bins), inv_width_(bins / (max - min)), bins_(bins) {
  centres_.resize(static_cast<std::size_t>(bins));
  edges_.resize(static_cast<std::size_t>(bins) + 1);
  for (int i = 0; i < bins; ++i) centres_[static_cast<std::size_t>(i)] = min_ + (i + 0.5) * width_;
  for (int i = 0; i <= bins; ++i) edges_[static_cast<std::size_t>(i)] = min_ + i * width_;
}

BinAxis BinAxis::from_centres(std::vector<double> centres) {
  BinAxis a;
  const std::size_t n = centres.size();
  a.edges_.resize(n + 1);
  for (std::size_t i = 1; i < n; ++i) a.edges_[i] = 0.5 * (centres[i - 1] + centres[i]);
  a.edges_[0] = centres[0] - 0.5 * (centres[1] - centres[0]);
  a.edges_[n] = centres[n - 1] + 0.5 * (centres[n - 1] - centres[n - 2]);
  a.bins_ = static_cast<int>(n);
  a.min_ = a.edges_.front();
  a.max_ = a.edges_.back();
  a.width_ = (a.max_ - a.min_) / a.bins_;
  a.inv_width_ = 1.0 / a.width_;
  a.uniform_ = false;
  a.centres_ = std::move(centres);
  return a;
}

int BinAxis::bin_from_edges(double value) const {
  return static_cast<int>(std::upper_bound(edges_.begin(), edges_.end(), value) - edges_.begin()) - 1;
}

namespace {

// The built-ins from the start; register_angular_binning() adds to it.
detail::TagRegistry<AngularBinning>& registry() {
  static detail::TagRegistry<AngularBinning> r(
      "angular_binning", "angular binning",
      {{AngularBinning::spherical, [](const GeometryParams& p) { return std::make_shared<SphericalBinning>(p); }},
       {AngularBinning::pinhole, [](const GeometryParams& p) { return std::make_shared<PinholeBinning>(p); }},
       {AngularBinning::lidar_rings, [](const GeometryParams& p) { return std::make_shared<LidarRingsBinning>(p); }}});
  return r;
}

}  // namespace

void register_angular_binning(const std::string& tag, AngularBinningFactory factory) {
  registry().add(tag, std::move(factory));
}

std::vector<std::string> registered_angular_binnings() { return registry().tags(); }

bool is_registered_angular_binning(const std::string& tag) { return registry().has(tag); }

std::shared_ptr<const AngularBinning> make_angular_binning(const GeometryParams& params) {
  return registry().make(params.angular_binning, params);
}

}  // namespace occ_improve
