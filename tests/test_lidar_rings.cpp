// The lidar_rings binning (a spinning LiDAR's range image), added without touching insertion, surface or
// improvement: its geometry and validation, and insertion and improvement of a generated scene rendered
// through it against the dense reference, ray by ray (save/load: test_map_io.cpp; export: octomap/).
#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/lidar_rings_binning.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/surface.hpp"
#include "reference/reference.hpp"
#include "support/lidar_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

namespace occ_improve {
namespace {

constexpr double kDeg = M_PI / 180.0;

TEST(LidarRings, RowsAreTheRingsTopToBottomAndColumnsTheAzimuthSteps) {
  const SensorPreset p = lidar_rings();  // a VLP-16: rings -15..15 deg every 2 deg, 1800 steps
  const GridGeometry g(p.geometry);
  EXPECT_EQ(g.binning(), AngularBinning::lidar_rings);
  EXPECT_EQ(g.binning().unit(), AngularUnit::radians);
  ASSERT_EQ(g.height(), 16);
  ASSERT_EQ(g.width(), 1800);
  EXPECT_FALSE(g.elevation().uniform());
  // y points down: the ring a datasheet lists at +15 deg (up) is row 0, at phi = -15 deg.
  EXPECT_NEAR(g.elevation().centre(0), -15 * kDeg, 1e-12);
  EXPECT_NEAR(g.elevation().centre(15), 15 * kDeg, 1e-12);
  EXPECT_NEAR(g.elevation().lower(0), -16 * kDeg, 1e-12);
  EXPECT_NEAR(g.azimuth().width(), 0.2 * kDeg, 1e-12);
  // A point 2 m away on the ring at -5 deg (up: phi = +5 deg) and at azimuth 30.1 deg.
  const Eigen::Vector3d q = g.direction_at(30.1 * kDeg, 5 * kDeg) * 2.0;
  RayPosition r;
  ASSERT_TRUE(g.project(q.x(), q.y(), q.z(), r));
  EXPECT_EQ(r.vertical_bin, 10);  // phi = -15, -13, ..., 5 is the 11th ring
  EXPECT_EQ(r.horizontal_bin, 1050);  // (30.1 + 180) / 0.2
  EXPECT_NEAR(r.depth, 2.0, 1e-12);  // the depth coordinate is the range
  // Halfway-to-the-neighbour edges: 0.9 deg above a ring is still its row, 1.1 deg the next.
  const Eigen::Vector3d near = g.direction_at(0.0, 5.9 * kDeg), next = g.direction_at(0.0, 6.1 * kDeg);
  ASSERT_TRUE(g.project(near.x(), near.y(), near.z(), r));
  EXPECT_EQ(r.vertical_bin, 10);
  ASSERT_TRUE(g.project(next.x(), next.y(), next.z(), r));
  EXPECT_EQ(r.vertical_bin, 11);
  // Beyond the outer rows' edges (half a gap beyond the outer rings): outside the field of view.
  const Eigen::Vector3d above = g.direction_at(0.0, -16.5 * kDeg);
  EXPECT_FALSE(g.project(above.x(), above.y(), above.z(), r));
  // The sensor's sigmas in the binning's unit (radians): one step's quantisation, and the beam's vertical
  // divergence (1.5 mrad); 0 takes the narrowest row's quantisation, as for a pixel.
  EXPECT_NEAR(p.model.sigma_azimuth_rad, 0.2 * kDeg / std::sqrt(12.0), 1e-15);
  EXPECT_EQ(p.model.sigma_elevation_rad, 1.5e-3);
  EXPECT_EQ(SensorModel(p.model).sigma_vertical(g.binning()), p.model.sigma_elevation_rad);
  LidarRingsOptions as_pixels;
  as_pixels.sigma_elevation_rad = 0;
  EXPECT_NEAR(lidar_rings(as_pixels).model.sigma_elevation_rad, 2 * kDeg / std::sqrt(12.0), 1e-12);
}

// A VLP-16 1.73 m above flat ground (a street scan's ground rings, 6.7-33 m away), one return per column
// at the column's centre with 2 cm of range noise. Each ring's surface must be at its own range. With the
// rows' quantisation as the elevation sigma (the default before: 0.58 deg, whose 2 sigma reaches into the
// next ring's row) each return's free space carved its neighbouring rings, and 89-100 % of the ground columns put
// their surface at the next ring's range (a held-out trial); the beam's divergence keeps each to its ring.
TEST(LidarRings, GroundRingsKeepTheirOwnRange) {
  const auto wrong_share = [](const SensorPreset& p) {
    const GridGeometry g(p.geometry);
    ColumnGrid grid(g);
    std::mt19937 random(3);
    std::normal_distribution<double> noise(0.0, 0.02);
    std::vector<Eigen::Vector3f> points;
    std::vector<std::pair<ColumnIndex, double>> truth;
    for (int e = 0; e < g.height(); ++e)
      for (int a = 0; a < g.width(); ++a) {
        const Eigen::Vector3d d = g.direction_at(g.azimuth().centre(a), g.elevation().centre(e));
        if (!(d.y() > 0)) continue;  // optical frame: y down, the ground is y = 1.73
        const double range = 1.73 / d.y();
        if (range > 45.0) continue;
        points.push_back((d * (range + noise(random))).cast<float>());
        truth.emplace_back(g.column(a, e), range);
      }
    insert_points(grid, SensorModel(p.model), PointSpan::from(points));
    const SurfaceMap surface = compute_surface(grid);
    std::size_t wrong = 0;
    for (const auto& [c, range] : truth) wrong += std::abs(surface.depth_m[c] - range) > 0.1 ? 1 : 0;
    EXPECT_GT(truth.size(), 10000u);
    return static_cast<double>(wrong) / static_cast<double>(truth.size());
  };
  const double beams = wrong_share(lidar_rings());
  LidarRingsOptions as_pixels;
  as_pixels.sigma_elevation_rad = 0;
  const double pixels = wrong_share(lidar_rings(as_pixels));
  std::printf("ground columns off their ring's range by > 0.1 m: %.3f (rows as pixels: %.3f)\n", beams, pixels);
  EXPECT_LT(beams, 0.01);
  EXPECT_GT(pixels, 0.5);
}

std::string parameter_error(const LidarRingsOptions& o) {
  try {
    lidar_rings(o);
  } catch (const InvalidParameter& e) {
    return e.what();
  }
  return "";
}

std::string geometry_error(const GeometryParams& g) {
  try {
    g.validate();
  } catch (const InvalidParameter& e) {
    return e.what();
  }
  return "";
}

TEST(LidarRings, BadRingTablesAreRefusedNamingTheField) {
  LidarRingsOptions o;
  o.ring_elevations_deg = {-15, -13, -11, -12, -7};  // not monotonic at index 3
  EXPECT_NE(parameter_error(o).find("ring_elevations_deg[3]"), std::string::npos) << parameter_error(o);
  o.ring_elevations_deg = {10, 5, 5};  // a repeat
  EXPECT_NE(parameter_error(o).find("ring_elevations_deg[2]"), std::string::npos) << parameter_error(o);
  o.ring_elevations_deg = {2};
  EXPECT_NE(parameter_error(o).find("ring_elevations_deg size"), std::string::npos) << parameter_error(o);
  // The lowest row would reach past straight down: named as given (it read "row_elevations_rad (last) =
  // 1.65806", another field, in radians, with the optical frame's sign).
  o.ring_elevations_deg = {15, 0, -89.5};
  EXPECT_NE(parameter_error(o).find("ring_elevations_deg[2] = -89.5"), std::string::npos) << parameter_error(o);
  o.ring_elevations_deg = {0, 45, 95};
  EXPECT_NE(parameter_error(o).find("ring_elevations_deg[2] = 95 is invalid: must be in (-90, 90) deg"), std::string::npos)
      << parameter_error(o);
  o.ring_elevations_deg = {0, std::nan(""), 3};
  EXPECT_NE(parameter_error(o).find("ring_elevations_deg[1]"), std::string::npos) << parameter_error(o);
  o = LidarRingsOptions{};
  o.sigma_elevation_rad = -1e-3;
  EXPECT_NE(parameter_error(o).find("sigma_elevation_rad"), std::string::npos) << parameter_error(o);

  GeometryParams g = lidar_rings().geometry;
  g.elevation_bins = 15;
  EXPECT_NE(geometry_error(g).find("elevation_bins"), std::string::npos) << geometry_error(g);
  g = lidar_rings().geometry;
  std::swap(g.row_elevations_rad[4], g.row_elevations_rad[5]);
  EXPECT_NE(geometry_error(g).find("row_elevations_rad[5]"), std::string::npos) << geometry_error(g);
  g = lidar_rings().geometry;
  g.azimuth_min_rad = -4.0;
  EXPECT_NE(geometry_error(g).find("azimuth_min_rad"), std::string::npos) << geometry_error(g);
  // No ring table at all (a GeometryParams switched to lidar_rings): the rows were built before the
  // check and the process crashed.
  GeometryParams no_rings;
  no_rings.angular_binning = AngularBinning::lidar_rings;
  EXPECT_NE(geometry_error(no_rings).find("row_elevations_rad size"), std::string::npos) << geometry_error(no_rings);
  g = lidar_rings().geometry;
  g.angular_binning = "lidar_ringz";
  EXPECT_NE(geometry_error(g).find("'lidar_ringz' is not a registered binning"), std::string::npos)
      << geometry_error(g);
}

TEST(LidarRings, InsertionMatchesTheDenseReferenceRayByRay) {
  const SensorPreset p = test::small_lidar();
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  for (UpdateMode mode : {UpdateMode::exact, UpdateMode::clamped}) {
    GridOptions o;
    o.mode = mode;
    ColumnGrid fast(g, o);
    reference::DenseGrid ref(g, model, o);
    for (std::uint32_t seed : {1u, 2u}) {  // two scans: re-visits (and clamping)
      const auto points = test::lidar_scan(g, seed);
      const InsertionReport r = insert_points(fast, model, PointSpan::from(points));
      ref.insert(points);
      EXPECT_GT(r.points_inserted, 1000u);
    }
    const reference::SurfaceAgreement a = reference::compare_surfaces(fast, ref);
    EXPECT_GT(a.touched, static_cast<std::size_t>(0.7 * a.columns));
    EXPECT_GE(a.same_bin, static_cast<std::size_t>(0.999 * a.columns)) << a.same_bin << " / " << a.columns;
    EXPECT_LE(a.max_dp, 1e-4);
    if (mode == UpdateMode::exact) continue;
    // Clamped, voxel by voxel (exact-mode log-odds reach -1e3 in front of a return, where float sums
    // differ from the reference's doubles by more than 1e-4: the surfaces above are compared instead).
    EXPECT_LE(reference::max_log_odds_difference(fast, ref), 1e-4);
  }
}

// Eqs. 3-4 over the fast surface, against the reference in double: the per-row B_v tables of the
// uneven rings (rows 1.5 to 4 deg wide) give the reference's sums.
TEST(LidarRings, ImprovementMatchesTheDenseReferenceRayByRay) {
  const SensorPreset p = test::small_lidar();
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  ColumnGrid grid(g);
  insert_points(grid, model, PointSpan::from(test::lidar_scan(g)));
  const SurfaceMap surface = compute_surface(grid);
  const reference::ImprovementAgreement agreement = reference::compare_improvement(g, model, surface);
  EXPECT_LE(agreement.max_difference, 1e-5);
  EXPECT_GT(agreement.max_abs_reference, 0.1);  // not trivially flat
  const ImprovementMap fast = compute_improvement(g, model, surface);
  // Ray by ray (the scalar path) gives the row loop's values.
  for (int e = 0; e < g.height(); ++e)
    for (int a = 0; a < g.width(); a += 7)
      EXPECT_EQ(static_cast<float>(ray_improvement(g, model, surface, a, e)), fast.value[g.column(a, e)]);
  // The window reaches the neighbouring rings where they are close (1.5 deg apart at the horizon, row 5)
  // and not where they are far (2 deg at row 10): the rows a changed column's surface affects.
  const auto affected_rows = [&](int e) {
    ImprovementMap updated = fast;
    std::vector<int> rows;
    for (ColumnIndex c : update_improvement(g, model, surface, {g.column(48, e)}, updated))
      if (std::find(rows.begin(), rows.end(), g.elevation_bin_of(c)) == rows.end()) rows.push_back(g.elevation_bin_of(c));
    std::sort(rows.begin(), rows.end());
    return rows;
  };
  EXPECT_EQ(affected_rows(5), (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(affected_rows(10), (std::vector<int>{10}));
}

}  // namespace
}  // namespace occ_improve
