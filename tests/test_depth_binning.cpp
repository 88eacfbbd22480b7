// The depth axis as an open interface: DepthAxis's lookups against their definitions for the built-in
// binnings and one registered here (test_log: equal steps in log depth), validation of a binning's bins,
// and insertion and improvement through test_log against the dense reference, with insertion, surface and
// improvement unchanged (save/load: test_map_io.cpp).
#include "occ_improve/errors.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/surface.hpp"
#include "reference/reference.hpp"
#include "support/lidar_scene.hpp"
#include "support/log_depth_binning.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace occ_improve {
namespace {

// The definitions the bucket table and its fix-up must reproduce, by linear search.
int first_centre_above_by_search(const DepthAxis& d, double rho) {
  int b = 0;
  while (b < d.bins() && d.centre(b) <= rho) ++b;
  return b;
}

int bin_by_search(const DepthAxis& d, double rho) {
  if (!(rho >= d.min())) return -1;
  if (rho >= d.max()) return d.bins();
  int b = 0;
  while (!(rho < d.upper(b))) ++b;
  return b;
}

void expect_lookups_match_their_definitions(const DepthAxis& d) {
  std::vector<double> probes = {-1.0, 0.0, d.max(), 2 * d.max(), std::nan("")};
  for (int b = 0; b < d.bins(); ++b)
    for (double x : {d.lower(b), d.centre(b), d.upper(b)})
      for (double y : {x, std::nextafter(x, -1.0), std::nextafter(x, 1e9)}) probes.push_back(y);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(d.min() - 0.1, d.max() + 0.1);
  for (int i = 0; i < 20000; ++i) probes.push_back(uniform(random));
  for (double rho : probes) {
    ASSERT_EQ(d.first_centre_above(rho), first_centre_above_by_search(d, rho)) << d.binning() << " rho " << rho;
    ASSERT_EQ(d.bin(rho), bin_by_search(d, rho)) << d.binning() << " rho " << rho;
  }
}

TEST(DepthBinning, LookupsMatchTheirDefinitionsForEveryBinning) {
  test::register_log_depth_binning();
  expect_lookups_match_their_definitions(DepthAxis(DepthBinning::uniform, 0.0, 5.0, 512));
  expect_lookups_match_their_definitions(DepthAxis(DepthBinning::inverse_depth, 0.5, 8.0, 2048));
  expect_lookups_match_their_definitions(DepthAxis(DepthBinning::inverse_depth, 0.3, 7.7, 999));
  const DepthAxis log_axis(test::LogDepthBinning::kTag, 0.3, 8.0, 256);
  EXPECT_EQ(log_axis.binning(), "test_log");
  // Equal steps in log depth: every bin is (8 / 0.3)^(1/256) times as wide as the one before.
  EXPECT_NEAR((log_axis.upper(200) - log_axis.lower(200)) / (log_axis.upper(199) - log_axis.lower(199)),
              std::pow(8.0 / 0.3, 1.0 / 256), 1e-9);
  EXPECT_NEAR(log_axis.centre(0), std::sqrt(0.3 * log_axis.upper(0)), 1e-15);
  expect_lookups_match_their_definitions(log_axis);
}

std::string geometry_error(const GeometryParams& g) {
  try {
    GridGeometry{g};
  } catch (const InvalidParameter& e) {
    return e.what();
  }
  return "";
}

// A binning whose centres fall outside their bins.
class BrokenDepthBinning : public DepthBinning {
public:
  const char* tag() const override { return "test_broken"; }
  void bins(double min_m, double max_m, int bins, std::vector<double>& edges,
            std::vector<double>& centres) const override {
    edges.assign(static_cast<std::size_t>(bins) + 1, 0.0);
    for (int b = 0; b <= bins; ++b) edges[static_cast<std::size_t>(b)] = min_m + (max_m - min_m) * b / bins;
    centres.assign(edges.begin(), edges.end() - 1);  // on the lower edges
  }
};

TEST(DepthBinning, UnknownTagsAndBrokenBinsAreRefusedNamingThem) {
  GeometryParams g;
  g.depth_binning = "no_such_binning";
  EXPECT_NE(geometry_error(g).find("depth_binning = 'no_such_binning' is not a registered binning"), std::string::npos)
      << geometry_error(g);
  EXPECT_NE(geometry_error(g).find("inverse_depth"), std::string::npos) << "lists the registered tags";
  register_depth_binning("test_broken", [](const GeometryParams&) { return std::make_shared<BrokenDepthBinning>(); });
  g.depth_binning = "test_broken";
  EXPECT_NE(geometry_error(g).find("depth_binning 'test_broken': bin 0"), std::string::npos) << geometry_error(g);
  test::register_log_depth_binning();
  g.depth_binning = test::LogDepthBinning::kTag;  // the binning's own check: depth_min_m = 0
  EXPECT_NE(geometry_error(g).find("test_log"), std::string::npos) << geometry_error(g);
  g.depth_binning = DepthBinning::inverse_depth;
  EXPECT_NE(geometry_error(g).find("depth_min_m"), std::string::npos) << geometry_error(g);
}

SensorPreset log_lidar() {
  test::register_log_depth_binning();
  SensorPreset p = test::small_lidar();  // [0.3, 8 m) in 256 bins
  p.geometry.depth_binning = test::LogDepthBinning::kTag;
  return p;
}

// Eq. 1 through the fast insertion over log-spaced bins equals the dense reference's, voxel by voxel
// (clamped) and surface by surface (both modes).
TEST(DepthBinning, InsertionThroughARegisteredBinningMatchesTheDenseReference) {
  const SensorPreset p = log_lidar();
  const GridGeometry g(p.geometry);
  ASSERT_EQ(g.depth().binning(), "test_log");
  const SensorModel model(p.model);
  for (UpdateMode mode : {UpdateMode::exact, UpdateMode::clamped}) {
    GridOptions o;
    o.mode = mode;
    ColumnGrid fast(g, o);
    reference::DenseGrid ref(g, model, o);
    for (std::uint32_t seed : {1u, 2u}) {
      const auto points = test::lidar_scan(g, seed);
      EXPECT_GT(insert_points(fast, model, PointSpan::from(points)).points_inserted, 1000u);
      ref.insert(points);
    }
    const reference::SurfaceAgreement a = reference::compare_surfaces(fast, ref);
    EXPECT_GT(a.touched, a.columns * 7 / 10);
    EXPECT_GE(a.same_bin, a.columns * 999 / 1000) << a.same_bin << " / " << a.columns;
    EXPECT_LE(a.max_dp, 1e-4);
    if (mode == UpdateMode::exact) continue;  // exact log-odds reach -1e3: float vs double (test_lidar_rings)
    EXPECT_LE(reference::max_log_odds_difference(fast, ref), 1e-4);
  }
}

TEST(DepthBinning, ImprovementThroughARegisteredBinningMatchesTheDenseReference) {
  const SensorPreset p = log_lidar();
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  ColumnGrid grid(g);
  insert_points(grid, model, PointSpan::from(test::lidar_scan(g)));
  const SurfaceMap surface = compute_surface(grid);
  const reference::ImprovementAgreement agreement = reference::compare_improvement(g, model, surface);
  EXPECT_LE(agreement.max_difference, 1e-5);
  EXPECT_GT(agreement.max_abs_reference, 0.1);
  // The surface depths are the log bins' centres (a peak's bin or the midpoint of a saturated run's).
  std::size_t at_centre = 0, known = 0;
  for (std::size_t c = 0; c < surface.size(); ++c) {
    if (surface.unknown[c] || surface.bin[c] >= g.depth().bins()) continue;
    ++known;
    at_centre += std::abs(surface.depth_m[c] - static_cast<float>(g.depth().centre(surface.bin[c]))) < 1e-6f;
  }
  EXPECT_GT(known, 1000u);
  EXPECT_GT(at_centre, known / 2);
}

}  // namespace
}  // namespace occ_improve
