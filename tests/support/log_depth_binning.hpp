#pragma once
// A depth binning the library does not have, registered by the tests only ("test_log"): bins of equal
// width in log(depth), each centre the geometric mean of its edges. It proves the depth axis is an open
// interface: insertion, surface, improvement and map files use it without knowing it (test_depth_binning.cpp,
// test_map_io.cpp).
#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/depth_binning.hpp"
#include "occ_improve/geometry/geometry.hpp"

#include <cmath>
#include <memory>

namespace occ_improve::test {

class LogDepthBinning : public DepthBinning {
public:
  static constexpr const char* kTag = "test_log";
  explicit LogDepthBinning(const GeometryParams& p) {
    if (!(p.depth_min_m > 0)) throw InvalidParameter("depth_min_m must be > 0 for test_log");
  }
  const char* tag() const override { return kTag; }
  void bins(double min_m, double max_m, int bins, std::vector<double>& edges,
            std::vector<double>& centres) const override {
    const double step = std::log(max_m / min_m) / bins;
    edges.resize(static_cast<std::size_t>(bins) + 1);
    centres.resize(static_cast<std::size_t>(bins));
    for (int b = 0; b <= bins; ++b) edges[static_cast<std::size_t>(b)] = min_m * std::exp(b * step);
    edges.front() = min_m;
    edges.back() = max_m;
    for (int b = 0; b < bins; ++b)
      centres[static_cast<std::size_t>(b)] = std::sqrt(edges[static_cast<std::size_t>(b)] * edges[static_cast<std::size_t>(b) + 1]);
  }
};

inline void register_log_depth_binning() {
  register_depth_binning(LogDepthBinning::kTag,
                         [](const GeometryParams& p) { return std::make_shared<LogDepthBinning>(p); });
}

}  // namespace occ_improve::test
