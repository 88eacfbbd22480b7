// The improvement map (eqs. 3-4, CONVENTIONS 7-8): the fast path against the dense double reference ray by
// ray, the one-ray definition against the full map, the incremental update, and the paper's picture.
#include "occ_improve/errors.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/maps/surface.hpp"
#include "reference/reference.hpp"
#include "support/small_camera.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace occ_improve {
namespace {

GridGeometry paper_crop(int a0, int e0, int w, int h) {
  return reference::crop(GridGeometry(kinect_v1_paper().geometry), a0, e0, w, h);
}

// The fast path's input built from the reference's own surfaces, so that eqs. 3-4 are compared alone.
SurfaceMap surface_from(const GridGeometry& g, const std::vector<reference::DenseGrid::Surface>& ref) {
  SurfaceMap s;
  s.width = g.width();
  s.height = g.height();
  for (const auto& r : ref) {
    s.depth_m.push_back(static_cast<float>(r.depth_m));
    s.probability.push_back(static_cast<float>(r.probability));
    s.bin.push_back(r.bin);
    s.unknown.push_back(r.unknown ? 1 : 0);
  }
  return s;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct ReferenceScene {
  GridGeometry geometry;
  SensorModel model;
  ColumnGrid fast;
  reference::DenseGrid ref;
};

// The sample scene's box, pole, wall and shadow band, exact mode.
ReferenceScene make_reference_scene(const SensorPreset& preset, int a0, int e0, int w, int h) {
  const GridGeometry g = reference::crop(GridGeometry(preset.geometry), a0, e0, w, h);
  GridOptions o;
  o.mode = UpdateMode::exact;
  ReferenceScene s{g, SensorModel(preset.model), ColumnGrid(g, o), reference::DenseGrid(g, SensorModel(preset.model), o)};
  const auto points = sample::generate_scene().points();
  insert_points(s.fast, s.model, PointSpan::from(points));
  s.ref.insert(points);
  return s;
}

TEST(Improvement, EquationsMatchReferenceOnReferenceSurface) {
  SensorPreset p = kinect_v1_paper();
  p.geometry.depth_bins = 256;
  const ReferenceScene s = make_reference_scene(p, 150, 200, 48, 40);
  std::vector<reference::DenseGrid::Surface> surfaces(s.geometry.column_count());
  for (std::size_t c = 0; c < surfaces.size(); ++c) surfaces[c] = s.ref.surface(c);
  const std::vector<double> expected = reference::improvement_map(s.geometry, s.model, surfaces);
  const ImprovementMap fast = compute_improvement(s.geometry, s.model, surface_from(s.geometry, surfaces));
  double max_d = 0, max_abs = 0;
  for (std::size_t c = 0; c < expected.size(); ++c) {
    max_d = std::max(max_d, std::abs(expected[c] - fast.value[c]));
    max_abs = std::max(max_abs, std::abs(expected[c]));
  }
  EXPECT_LE(max_d, 1e-4);
  EXPECT_GT(max_abs, 0.1);  // the scene is not trivially flat
}

// The float kernel's own error (polynomial exp, float sums) against the double formula on the same
// surface, in clamped mode where P reaches 0.001 / 0.999 and 1 - P is least accurate in float.
TEST(Improvement, FloatKernelIsWithinItsDocumentedBound) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g = paper_crop(140, 190, 96, 80);
  const SensorModel model(p.model);
  ColumnGrid grid(g);
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    sample::SceneOptions o;
    o.seed = seed;
    insert_points(grid, model, PointSpan::from(sample::generate_scene(o).points()));
  }
  const SurfaceMap surface = compute_surface(grid);
  EXPECT_LE(reference::compare_improvement(g, model, surface).max_difference, 1e-5);
}

TEST(Improvement, PipelineMatchesReferenceRayByRay) {
  // Paper preset and the range-dependent preset (sigma evaluated at the simulated depth).
  SensorPreset paper = kinect_v1_paper();
  paper.geometry.depth_bins = 256;
  // Range-dependent noise over spherical bins and over the pixel-native binning.
  SensorPreset spherical = kinect_v1_spherical(), pixel_native = kinect_v1();
  spherical.geometry.depth_bins = pixel_native.geometry.depth_bins = 512;
  for (const auto& [preset, a0, e0] :
       {std::tuple{paper, 300, 220}, std::tuple{spherical, 280, 240}, std::tuple{pixel_native, 280, 240}}) {
    const ReferenceScene s = make_reference_scene(preset, a0, e0, 32, 32);
    const std::vector<double> expected = reference::improvement_map(s.ref);
    const SurfaceMap surface = compute_surface(s.fast);
    const ImprovementMap fast = compute_improvement(s.geometry, s.model, surface);
    // Rays whose 3 x 3 neighbourhood has the reference's surface bins (the surface test covers the rest).
    std::size_t compared = 0;
    double max_d = 0;
    for (int e = 1; e + 1 < s.geometry.height(); ++e)
      for (int a = 1; a + 1 < s.geometry.width(); ++a) {
        bool same = true;
        for (int de = -1; de <= 1; ++de)
          for (int da = -1; da <= 1; ++da) {
            const ColumnIndex c = s.geometry.column(a + da, e + de);
            same = same && s.ref.surface(c).bin == surface.bin[c];
          }
        if (!same) continue;
        ++compared;
        const ColumnIndex j = s.geometry.column(a, e);
        max_d = std::max(max_d, std::abs(expected[j] - fast.value[j]));
      }
    EXPECT_GE(compared, static_cast<std::size_t>(0.98 * 30 * 30)) << preset.name;
    EXPECT_LE(max_d, 1e-4) << preset.name;
  }
}

TEST(Improvement, RayDefinitionEqualsFullMapForAnyThreadCount) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  ColumnGrid grid(g);
  insert_points(grid, model, PointSpan::from(sample::generate_scene().points()));
  const SurfaceMap surface = compute_surface(grid);
  const ImprovementMap one = compute_improvement(g, model, surface, 1);
  const ImprovementMap two = compute_improvement(g, model, surface, 2);
  EXPECT_EQ(one.value, two.value);
  std::mt19937 rng(3);
  for (int n = 0; n < 2000; ++n) {
    const int a = static_cast<int>(rng() % static_cast<unsigned>(g.width()));
    const int e = static_cast<int>(rng() % static_cast<unsigned>(g.height()));
    ASSERT_NEAR(ray_improvement(g, model, surface, a, e), one.value[g.column(a, e)], 1e-6) << a << ", " << e;
  }
  // Corners and edges: the window is clipped to the grid.
  for (const auto& [a, e] : {std::pair{0, 0}, std::pair{g.width() - 1, g.height() - 1}, std::pair{0, 100}})
    EXPECT_NEAR(ray_improvement(g, model, surface, a, e), one.value[g.column(a, e)], 1e-6);
}

// The full map reuses a row's values for a row with bitwise the same inputs (an empty map's interior
// rows): every ray still equals the one-ray definition, on an empty map and beside a measured band, for a
// pixel-native camera, the paper's spherical grid, the spherical Kinect preset (columns outside the
// camera: NaN, which must not leak into a reused row) and uneven LiDAR rings (rows of unequal angular
// terms).
TEST(Improvement, RowsWithTheSameInputsStillMatchTheOneRayDefinition) {
  LidarRingsOptions rings;  // unevenly spaced rings whose windows span their neighbours: B differs by row
  rings.ring_elevations_deg = {-25, -15, -10, -7, -5, -4, -3, -2, -1, 0, 1, 2};
  rings.sigma_elevation_rad = 0.02;
  rings.azimuth_steps = 90;
  for (const SensorPreset& p :
       {kinect_v1(test::small_camera()), kinect_v1_paper(), kinect_v1_spherical(test::small_camera()), lidar_rings(rings)}) {
    const GridGeometry g = p.geometry.azimuth_bins > 400 ? reference::crop(GridGeometry(p.geometry), 0, 0, 80, 60)
                                                         : GridGeometry(p.geometry);
    const SensorModel model(p.model);
    ColumnGrid grid(g);
    for (const bool measured : {false, true}) {
      if (measured) {  // a band of rows measured at 2 m, the rest of the grid empty
        std::vector<Eigen::Vector3f> points;
        for (int a = 0; a < g.width(); ++a)
          for (int e = g.height() / 3; e < g.height() / 2; ++e) points.push_back(2.0f * g.direction(a, e).cast<float>());
        insert_points(grid, model, PointSpan::from(points));
      }
      const SurfaceMap surface = compute_surface(grid);
      const ImprovementMap map = compute_improvement(g, model, surface, 1);
      std::size_t unobservable = 0;
      for (int e = 0; e < g.height(); ++e)
        for (int a = 0; a < g.width(); ++a) {
          const auto where = [&] {  // streamed only when an assertion fails
            return p.name + (measured ? " with a band" : " empty") + " at " + std::to_string(a) + ", " + std::to_string(e);
          };
          if (!g.observable(g.column(a, e))) {
            ++unobservable;
            ASSERT_TRUE(std::isnan(map.value[g.column(a, e)])) << where();
            continue;
          }
          ASSERT_NEAR(ray_improvement(g, model, surface, a, e), map.value[g.column(a, e)], 1e-6) << where();
        }
      if (p.name == "kinect_v1_spherical") {
        EXPECT_GT(unobservable, 0u);  // the case the NaN check is for
      }
    }
  }
}

// k sigma exactly half a bin: whether the neighbour bin overlaps the box depends on the rounding of each
// bin's centre, so windows differ from bin to bin (the row loop's masked path). The full map still equals
// the one-ray definition everywhere.
TEST(Improvement, WindowsOnBinBoundariesStillMatchTheOneRayDefinition) {
  GeometryParams gp;
  gp.azimuth_bins = 200;
  gp.elevation_bins = 50;
  gp.azimuth_min_rad = -0.1;
  gp.azimuth_max_rad = 0.1;  // 1 mrad bins
  gp.elevation_min_rad = -0.025;
  gp.elevation_max_rad = 0.025;
  gp.depth_bins = 128;
  const GridGeometry g(gp);
  SensorModelParams mp;
  mp.sigma_azimuth_rad = mp.sigma_elevation_rad = 0.25e-3;  // k sigma = 0.5 mrad = half a bin
  const SensorModel model(mp);
  ColumnGrid grid(g);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.09f, 0.09f), v(-0.02f, 0.02f), d(1.0f, 4.0f);
  std::vector<Eigen::Vector3f> points;
  for (int n = 0; n < 6000; ++n) points.push_back(Eigen::Vector3f(u(rng), v(rng), 1.0f).normalized() * d(rng));
  insert_points(grid, model, PointSpan::from(points));
  const SurfaceMap surface = compute_surface(grid);
  const ImprovementMap map = compute_improvement(g, model, surface, 1);
  for (int e = 0; e < g.height(); ++e)
    for (int a = 0; a < g.width(); ++a)
      ASSERT_NEAR(ray_improvement(g, model, surface, a, e), map.value[g.column(a, e)], 1e-6) << a << ", " << e;
}

// A large update (over 20000 rays: the parallel row loop) on the threads the caller gives: the same values
// on one thread and on two, those of the full map; a negative count is refused.
TEST(Improvement, IncrementalUpdateRunsOnTheThreadsGiven) {
  const SensorPreset p = kinect_v1(kinect_v1_intrinsics());
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  ColumnGrid grid(g);
  const auto points = sample::generate_scene().points();
  insert_points(grid, model, PointSpan::from(points));
  SurfaceMap surface = compute_surface(grid);
  ImprovementMap one = compute_improvement(g, model, surface), two = one;
  std::vector<ColumnIndex> changed;
  for (int e = 100; e < 200; ++e)
    for (int a = 0; a < g.width(); a += 2) {
      const ColumnIndex c = g.column(a, e);
      surface.depth_m[c] *= 1.01f;
      changed.push_back(c);
    }
  const std::vector<ColumnIndex> rays_one = update_improvement(g, model, surface, changed, one, 1);
  const std::vector<ColumnIndex> rays_two = update_improvement(g, model, surface, changed, two, 2);
  EXPECT_GT(rays_one.size(), 20000u);
  EXPECT_EQ(rays_one, rays_two);
  EXPECT_EQ(one.value, two.value);
  EXPECT_EQ(one.value, compute_improvement(g, model, surface, 1).value);
  EXPECT_THROW(update_improvement(g, model, surface, changed, one, -1), InvalidParameter);
}

TEST(Improvement, IncrementalUpdateRecomputesExactlyTheAffectedRays) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g = paper_crop(100, 100, 64, 48);
  const SensorModel model(p.model);
  ColumnGrid grid(g);
  const auto points = sample::generate_scene().points();
  insert_points(grid, model, PointSpan::from(points));
  SurfaceMap surface = compute_surface(grid);
  ImprovementMap map = compute_improvement(g, model, surface);
  // Change a few surfaces by hand and update.
  const std::vector<ColumnIndex> changed = {g.column(0, 0), g.column(10, 20), g.column(63, 47)};
  for (const ColumnIndex c : changed) {
    surface.depth_m[c] = 2.0f;
    surface.probability[c] = 0.9f;
    surface.unknown[c] = 0;
  }
  const std::vector<ColumnIndex> rays = update_improvement(g, model, surface, changed, map);
  // The paper preset's window is 3 x 3: 4 + 9 + 4 rays.
  EXPECT_EQ(rays.size(), 17u);
  EXPECT_TRUE(std::is_sorted(rays.begin(), rays.end()));
  const ImprovementMap full = compute_improvement(g, model, surface);
  for (std::size_t c = 0; c < full.value.size(); ++c) ASSERT_NEAR(map.value[c], full.value[c], 1e-6) << c;
  // An empty map is computed in full.
  ImprovementMap empty;
  EXPECT_EQ(update_improvement(g, model, surface, {}, empty).size(), g.column_count());
  EXPECT_EQ(empty.value, full.value);
  // Rows with many affected rays take the row loop over spans of them (gaps shorter than 16 rays bridged,
  // longer ones skipped): every ray the full map's value (a span ending one ray early leaves stale ones).
  std::vector<ColumnIndex> many;
  for (int a : {0, 3, 6, 9, 30, 33, 55, 63}) many.push_back(g.column(a, 20));
  for (const ColumnIndex c : many) surface.depth_m[c] = 1.5f;
  update_improvement(g, model, surface, many, map);
  const ImprovementMap after = compute_improvement(g, model, surface);
  for (std::size_t c = 0; c < after.value.size(); ++c) ASSERT_NEAR(map.value[c], after.value[c], 1e-6) << c;
}

// CONVENTIONS 7's picture with the paper preset on the sample frame, as medians over masks of 3 x 3 windows.
// "Observed once" means one measurement close to the column's centre ray (P of a single centred
// measurement is P_s(0, 0) = 0.824; eq. 3 then gives 0.135). Most columns are not so aligned: 640 uniform
// bins of 1.55 mrad meet pinhole pixels of 1.9 mrad (the paper's moire), a measurement half a bin off the
// centre leaves P ~ 0.5 and the ray is worth almost as much as an unknown one.
TEST(Improvement, PaperPictureOnTheSampleScene) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g(p.geometry);
  const SensorModel model(p.model);
  ColumnGrid grid(g);  // clamped, as a user runs it
  insert_points(grid, model, PointSpan::from(sample::generate_scene().points()));
  const SurfaceMap s = compute_surface(grid);
  const ImprovementMap imp = compute_improvement(g, model, s);
  std::vector<double> unknown, once, beyond, far_side_of_edge, beside_hole;
  for (int e = 1; e + 1 < g.height(); ++e)
    for (int a = 1; a + 1 < g.width(); ++a) {
      const ColumnIndex j = g.column(a, e);
      bool all_unknown = true, all_known = true, all_beyond = true;
      int unknown_neighbours = 0;
      float lo = 1e9f, hi = -1e9f;
      for (int de = -1; de <= 1; ++de)
        for (int da = -1; da <= 1; ++da) {
          const ColumnIndex i = g.column(a + da, e + de);
          all_unknown = all_unknown && s.unknown[i];
          unknown_neighbours += s.unknown[i];
          all_known = all_known && !s.unknown[i];
          all_beyond = all_beyond && s.bin[i] == g.depth().bins();
          lo = std::min(lo, s.depth_m[i]);
          hi = std::max(hi, s.depth_m[i]);
        }
      const bool in_range = all_known && hi < g.depth().max();
      if (all_unknown) unknown.push_back(imp.value[j]);
      if (all_beyond) beyond.push_back(imp.value[j]);
      if (in_range && hi - lo < 0.05f && s.probability[j] > 0.78f && s.probability[j] < 0.86f)
        once.push_back(imp.value[j]);
      if (in_range && s.depth_m[j] - lo > 0.5f) far_side_of_edge.push_back(imp.value[j]);
      if (!s.unknown[j] && s.bin[j] < g.depth().bins() && unknown_neighbours >= 3) beside_hole.push_back(imp.value[j]);
    }
  ASSERT_GT(unknown.size(), 100u);
  ASSERT_GT(once.size(), 100u);
  ASSERT_GT(beyond.size(), 100u);
  ASSERT_GT(far_side_of_edge.size(), 100u);
  EXPECT_NEAR(median(unknown), 0.32, 0.02);
  EXPECT_NEAR(median(once), 0.13, 0.03);
  EXPECT_NEAR(median(beyond), 0.0, 0.01);
  // A measurement of the far side would carve the near side's surface free: negative.
  EXPECT_LT(median(far_side_of_edge), -0.1);
  // Beside a no-data hole: each unknown neighbour (depth 0, in front) is carved from 1/2 to ~0.
  ASSERT_GT(beside_hole.size(), 100u);
  EXPECT_LT(median(beside_hole), -0.5);
}

// A plane at 2 m measured exactly once along every column's centre ray: every ray is worth ~0.135.
TEST(Improvement, CentredSingleObservationIsWorthAboutOneEighth) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g = paper_crop(300, 220, 24, 20);
  const SensorModel model(p.model);
  ColumnGrid grid(g);
  std::vector<Eigen::Vector3f> points;
  for (int e = 0; e < g.height(); ++e)
    for (int a = 0; a < g.width(); ++a) points.push_back(g.point(a, e, 2.0 + 1e-3).cast<float>());
  insert_points(grid, model, PointSpan::from(points));
  const SurfaceMap s = compute_surface(grid);
  const ImprovementMap imp = compute_improvement(g, model, s);
  std::vector<double> interior;
  for (int e = 1; e + 1 < g.height(); ++e)
    for (int a = 1; a + 1 < g.width(); ++a) interior.push_back(imp.value[g.column(a, e)]);
  EXPECT_NEAR(median(interior), 0.135, 0.01);
  EXPECT_NEAR(s.probability[g.column(5, 5)], 0.824, 0.01);
}

TEST(Improvement, BadInputThrows) {
  const SensorPreset p = kinect_v1_paper();
  const GridGeometry g = paper_crop(0, 0, 16, 8);
  const SensorModel model(p.model);
  const SurfaceMap surface = compute_surface(ColumnGrid(g));
  EXPECT_THROW(ray_improvement(g, model, surface, -1, 0), InvalidParameter);
  EXPECT_THROW(ray_improvement(g, model, surface, 0, 8), InvalidParameter);
  EXPECT_THROW(compute_improvement(g, model, surface, -1), InvalidParameter);
  const SurfaceMap other = compute_surface(ColumnGrid(paper_crop(0, 0, 8, 8)));
  EXPECT_THROW(compute_improvement(g, model, other), InvalidInput);
  ImprovementMap wrong = compute_improvement(paper_crop(0, 0, 8, 8), model, other);
  EXPECT_THROW(update_improvement(g, model, surface, {}, wrong), InvalidInput);
  ImprovementMap map = compute_improvement(g, model, surface);
  EXPECT_THROW(update_improvement(g, model, surface, {static_cast<ColumnIndex>(g.column_count())}, map), InvalidInput);
}

}  // namespace
}  // namespace occ_improve
