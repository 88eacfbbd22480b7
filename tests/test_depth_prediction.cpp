// predict_depth: nearest sample in chessboard distance within a radius; the linear rule over the samples'
// Delaunay triangulation, never across a depth discontinuity; the triangulation itself.
#include "occ_improve/planning/depth_prediction.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/planning/sample_triangulation.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include "support/expect_throw.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>

namespace occ_improve {
namespace {

SurfaceMap unknown_surface(int w, int h) {
  SurfaceMap s;
  s.width = w;
  s.height = h;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  s.depth_m.assign(n, 0.0f);
  s.probability.assign(n, 0.5f);
  s.bin.assign(n, -1);
  s.unknown.assign(n, 1);
  return s;
}

void measure(SurfaceMap& s, int x, int y, float depth, float p = 0.8f) {
  s.set(static_cast<std::size_t>(y * s.width + x), {depth, p, 10, false});
}

// kSampleProbabilityMin is eq. 1 on the ray for a return at B = 3, and lies between what a pixel's own
// return gives its column (B = 0) and the most a neighbour's return gives it on the pixel-native grid (B = 12)
// even summed over a thousand frames of its 8 neighbours, each counted at B = 12 (0.5159).
TEST(DepthSample, ProbabilityMinIsEqOneAtTheColumnsEdge) {
  const double sigma = 0.01;
  EXPECT_NEAR(opdf(0.0, 3.0, sigma), kSampleProbabilityMin, 2e-4);
  EXPECT_GE(opdf(0.0, 3.0, sigma), kSampleProbabilityMin);
  EXPECT_GT(opdf(0.0, 0.0, sigma), 0.8);
  double neighbour_logit = 0;
  for (double t = -3; t <= 3; t += 0.01) neighbour_logit = std::max(neighbour_logit, logit_opdf(t * sigma, 12.0, sigma));
  EXPECT_GT(neighbour_logit, 0.0);
  EXPECT_LT(probability_from_logit(1000 * 8 * neighbour_logit), kSampleProbabilityMin);
}

// Four returns around a pixel of a fresh pixel-native map: their columns are samples; the pixel between
// them, which their OPDFs all reach (B = 12), holds P just above 0.5 at about their depth (one neighbour's
// edge alone stays within the surface's tie tolerance; four add up past it) and is not a sample, so a
// prediction fills it from the four.
TEST(DepthSample, NeighboursReturnsDoNotMakeAColumnASample) {
  PinholeIntrinsics camera;
  camera.width = 32;
  camera.height = 24;
  camera.cx = 15.5;
  camera.cy = 11.5;
  Mapper mapper(kinect_v1(camera));
  const int u = 10, v = 7;
  const float z = 2.0f;
  std::vector<Eigen::Vector3f> points;
  for (const auto& [du, dv] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}})
    points.emplace_back(static_cast<float>((u + du - camera.cx) * z / camera.fx),
                        static_cast<float>((v + dv - camera.cy) * z / camera.fy), z);
  mapper.insert(PointSpan::from(points));
  const SurfaceMap& s = mapper.surface();
  const auto column = [&](int x, int y) { return static_cast<std::size_t>(y * camera.width + x); };
  for (const auto& [du, dv] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
    EXPECT_TRUE(is_depth_sample(s, column(u + du, v + dv)));
    EXPECT_GT(s.probability[column(u + du, v + dv)], 0.8f);
  }
  const std::size_t between = column(u, v);
  EXPECT_GT(s.probability[between], 0.5f);  // P > 0.5, a sample by the rule before kSampleProbabilityMin
  EXPECT_LT(s.probability[between], 0.5001f);
  EXPECT_NEAR(s.depth_m[between], z, 0.02f);
  EXPECT_FALSE(is_depth_sample(s, between));
  const std::vector<float> samples = sample_depth_image(s);
  EXPECT_EQ(std::count_if(samples.begin(), samples.end(), [](float d) { return d > 0.0f; }), 4);
}

TEST(DepthPrediction, NearestSampleWithinTheRadius) {
  SurfaceMap s = unknown_surface(10, 5);
  measure(s, 1, 2, 1.0f);
  measure(s, 8, 2, 3.0f);
  measure(s, 5, 0, 2.0f, 0.5f);  // carved only: not a sample
  measure(s, 5, 4, 2.0f, 0.1f);  // free: not a sample
  DepthPredictionParams p;
  p.radius_columns = 3;
  const PredictedDepth d = predict_depth(s, p);
  EXPECT_FLOAT_EQ(d.depth_m[2 * 10 + 1], 1.0f);
  EXPECT_EQ(d.distance[2 * 10 + 1], 0);
  EXPECT_FLOAT_EQ(d.depth_m[0 * 10 + 3], 1.0f);  // chessboard distance 2 from (1, 2)
  EXPECT_EQ(d.distance[0 * 10 + 3], 2);
  EXPECT_FLOAT_EQ(d.depth_m[4 * 10 + 6], 3.0f);  // 2 from (8, 2), 5 from (1, 2)
  EXPECT_FLOAT_EQ(d.depth_m[0 * 10 + 5], 3.0f);  // its own carved surface is not used
  EXPECT_EQ(d.distance[2 * 10 + 5], 3);          // tie at 3 and 4: the nearest
  EXPECT_FLOAT_EQ(d.depth_m[2 * 10 + 5], 3.0f);
  p.radius_columns = 1;
  const PredictedDepth near = predict_depth(s, p);
  EXPECT_FLOAT_EQ(near.depth_m[2 * 10 + 5], 0.0f);
  EXPECT_EQ(near.distance[2 * 10 + 5], -1);
}

TEST(DepthPrediction, BadInputThrows) {
  DepthPredictionParams p;
  p.radius_columns = -1;
  EXPECT_THROW(predict_depth(unknown_surface(3, 3), p), InvalidParameter);
  SurfaceMap s = unknown_surface(3, 3);
  s.depth_m.pop_back();
  EXPECT_THROW(predict_depth(s), InvalidInput);
  const PredictedDepth none = predict_depth(unknown_surface(3, 3));
  for (float z : none.depth_m) EXPECT_EQ(z, 0.0f);
}

// Quadratic sigma only (Kinect): sigma(2 m) = 1.425e-3 x 4 = 5.7 mm, so 2 sigma = 11.4 mm.
SensorModel kinect_noise() {
  SensorModelParams p;
  p.sigma_depth_m = 0.0;
  p.sigma_depth_per_m2 = 1.425e-3;
  return SensorModel(p);
}

// Millimetres given as metres (2000 m where a Kinect's sigma is 5.7 km) made every triangle continuous and
// spread the values; a depth beyond the model's own sigma is refused, naming the pixel.
TEST(DepthPrediction, SamplesDeeperThanTheirSigmaAreNotMetres) {
  std::vector<float> depth(16 * 12, 0.0f);
  depth[5] = 2.0f;
  depth[40] = std::numeric_limits<float>::quiet_NaN();
  depth[100] = 2.5f;
  for (const auto rule : {DepthPredictionRule::nearest, DepthPredictionRule::linear}) {
    DepthPredictionParams params;
    params.rule = rule;
    EXPECT_NO_THROW(predict_dense_depth(depth, 16, 12, kinect_noise(), params));
    std::vector<float> millimetres = depth;
    millimetres[5] = 2000.0f;
    millimetres[100] = 2500.0f;
    try {
      predict_dense_depth(millimetres, 16, 12, kinect_noise(), params);
      ADD_FAILURE() << "millimetres were taken as metres";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("pixel (4, 6) holds depth 2500 m"), std::string::npos) << e.what();
    }
  }
}

TEST(DepthAgreement, CountsReferenceSamplesWithinTwoSigma) {
  SurfaceMap reference = unknown_surface(4, 1);
  for (int x = 0; x < 3; ++x) measure(reference, x, 0, 2.0f);  // column 3 unknown: not counted
  SurfaceMap map = unknown_surface(4, 1);
  measure(map, 0, 0, 2.011f);  // 11 mm off: within
  measure(map, 1, 0, 2.012f);  // 12 mm off: outside
  DepthPredictionParams p;
  p.radius_columns = 0;        // column 2 gets no prediction: disagrees
  const DepthAgreement a = depth_agreement(reference, predict_depth(map, p), kinect_noise());
  EXPECT_EQ(a.reference_samples, 3u);
  EXPECT_EQ(a.within, 1u);
  EXPECT_DOUBLE_EQ(a.share(), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(depth_agreement(reference, predict_depth(reference), kinect_noise()).share(), 1.0);
}

TEST(DepthAgreement, BadInputThrows) {
  const SurfaceMap reference = unknown_surface(4, 1);
  EXPECT_THROW(depth_agreement(reference, predict_depth(reference), kinect_noise(), 0.0), InvalidParameter);
  EXPECT_THROW(depth_agreement(reference, predict_depth(unknown_surface(2, 2)), kinect_noise()), InvalidInput);
  EXPECT_EQ(depth_agreement(reference, predict_depth(reference), kinect_noise()).share(), 0.0);
}

// A plane of the scene seen by a pinhole camera: inverse depth affine in the pixel, 2.0-2.15 m over the
// image, 0.25-0.4 sigma per pixel (sigma(2 m) = 5.7 mm).
float plane_z(int x, int y) { return static_cast<float>(1.0 / (0.5 - 0.0004 * x - 0.0003 * y)); }

// 5 % of the pixels at random plus every 8th pixel of the border (so that the hull is the whole image).
std::vector<float> sparse_plane(int w, int h, std::uint32_t seed) {
  std::vector<float> image(static_cast<std::size_t>(w) * h, 0.0f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool border = (x == 0 || y == 0 || x == w - 1 || y == h - 1) && (x % 8 == 0 || y % 8 == 0 || x == w - 1 || y == h - 1);
      if (border || u(rng) < 0.05) image[static_cast<std::size_t>(y * w + x)] = plane_z(x, y);
    }
  return image;
}

TEST(LinearDepthPrediction, ReproducesASlantedPlaneWhereNearestIsOff) {
  const int w = 64, h = 48;
  const std::vector<float> sparse = sparse_plane(w, h, 7);
  DepthPredictionParams p;
  p.rule = DepthPredictionRule::linear;
  const PredictedDepth linear = predict_dense_depth(sparse, w, h, kinect_noise(), p);
  p.rule = DepthPredictionRule::nearest;
  const PredictedDepth nearest = predict_dense_depth(sparse, w, h, kinect_noise(), p);
  double worst_linear = 0, worst_nearest = 0, sum_nearest = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t c = static_cast<std::size_t>(y * w + x);
      ASSERT_GE(linear.distance[c], 0);
      EXPECT_EQ(linear.distance[c], nearest.distance[c]);  // the same columns, the same distances
      const double sigma = kinect_noise().sigma_depth_at(plane_z(x, y));
      worst_linear = std::max(worst_linear, std::abs(linear.depth_m[c] - plane_z(x, y)) / sigma);
      const double e = std::abs(nearest.depth_m[c] - plane_z(x, y)) / sigma;
      worst_nearest = std::max(worst_nearest, e);
      sum_nearest += e;
    }
  EXPECT_LT(worst_linear, 0.02);  // float rounding only: 1/z is affine in the pixel
  EXPECT_GT(worst_nearest, 1.0);
  EXPECT_GT(sum_nearest / (w * h), 0.25);
}

TEST(LinearDepthPrediction, NeverInterpolatesAcrossADepthStep) {
  // Columns 0-9 at 1 m, 10-18 at 2 m; samples at x = 3, 7 (1 m) and 11, 15 (2 m) on rows 0 and 4.
  const int w = 19, h = 5;
  std::vector<float> sparse(static_cast<std::size_t>(w * h), 0.0f);
  for (const int y : {0, 4})
    for (const int x : {3, 7, 11, 15}) sparse[static_cast<std::size_t>(y * w + x)] = x < 10 ? 1.0f : 2.0f;
  DepthPredictionParams p;
  p.rule = DepthPredictionRule::linear;
  const PredictedDepth d = predict_dense_depth(sparse, w, h, kinect_noise(), p);
  for (std::size_t c = 0; c < d.depth_m.size(); ++c) EXPECT_TRUE(d.depth_m[c] == 1.0f || d.depth_m[c] == 2.0f) << c;
  EXPECT_FLOAT_EQ(d.depth_m[0 * w + 8], 1.0f);   // nearer to x = 7
  EXPECT_FLOAT_EQ(d.depth_m[0 * w + 9], 1.0f);   // as near to 7 as to 11: the nearer surface wins
  EXPECT_FLOAT_EQ(d.depth_m[2 * w + 9], 1.0f);   // equidistant from all four corners of the square
  EXPECT_FLOAT_EQ(d.depth_m[2 * w + 10], 2.0f);  // nearer to x = 11
  // A smaller threshold than the step's spread is still a step: 1 m apart is > 6 sigma(2 m) = 34 mm.
  p.discontinuity_sigmas = 1000.0;  // 5.7 m: now the step is interpolated
  const PredictedDepth smooth = predict_dense_depth(sparse, w, h, kinect_noise(), p);
  EXPECT_GT(smooth.depth_m[2 * w + 9], 1.0f);
  EXPECT_LT(smooth.depth_m[2 * w + 9], 2.0f);
}

TEST(LinearDepthPrediction, RespectsTheRadius) {
  // One triangle with a 20-column edge: interpolated with radius 12 (edges up to 24), not with radius 4.
  std::vector<float> sparse(21 * 11, 0.0f);
  sparse[0] = 2.0f;
  sparse[20] = 2.01f;
  sparse[10 * 21] = 2.0f;
  DepthPredictionParams p;
  p.rule = DepthPredictionRule::linear;
  p.radius_columns = 4;
  const PredictedDepth short_reach = predict_dense_depth(sparse, 21, 11, kinect_noise(), p);
  EXPECT_FLOAT_EQ(short_reach.depth_m[4], 2.0f);  // the nearest sample, 4 columns away
  EXPECT_EQ(short_reach.distance[10], -1);         // 10 columns from any sample: no prediction
  EXPECT_EQ(short_reach.depth_m[10], 0.0f);
  p.radius_columns = 12;
  const PredictedDepth long_reach = predict_dense_depth(sparse, 21, 11, kinect_noise(), p);
  EXPECT_NEAR(long_reach.depth_m[4], 1.0 / (0.8 / 2.0 + 0.2 / 2.01), 1e-6);
  EXPECT_NEAR(long_reach.depth_m[10], 1.0 / (0.5 / 2.0 + 0.5 / 2.01), 1e-6);
  // Same coverage as nearest: a column is predicted by linear exactly when it is by nearest.
  p.rule = DepthPredictionRule::nearest;
  const PredictedDepth nearest = predict_dense_depth(sparse, 21, 11, kinect_noise(), p);
  EXPECT_EQ(nearest.distance, long_reach.distance);
}

TEST(LinearDepthPrediction, SurfaceOverloadsAgreeWithTheSparseImage) {
  SurfaceMap s = unknown_surface(10, 6);
  measure(s, 1, 1, 1.0f);
  measure(s, 8, 1, 1.02f);
  measure(s, 4, 5, 1.01f);
  measure(s, 5, 3, 3.0f, 0.5f);  // not a sample
  const std::vector<float> image = sample_depth_image(s);
  EXPECT_EQ(image[1 * 10 + 1], 1.0f);
  EXPECT_EQ(image[3 * 10 + 5], 0.0f);
  DepthPredictionParams p;
  p.rule = DepthPredictionRule::linear;
  const PredictedDepth a = predict_depth(s, kinect_noise(), p), b = predict_dense_depth(image, 10, 6, kinect_noise(), p);
  EXPECT_EQ(a.depth_m, b.depth_m);
  EXPECT_GT(a.depth_m[3 * 10 + 5], 1.0f);  // inside the triangle: between its vertices
  EXPECT_LT(a.depth_m[3 * 10 + 5], 1.02f);
  p.rule = DepthPredictionRule::nearest;
  EXPECT_EQ(predict_depth(s, kinect_noise(), p).depth_m, predict_depth(s).depth_m);
}

using test::expect_throw_naming;

TEST(LinearDepthPrediction, BadInputThrowsNamingTheValue) {
  const SensorModel m = kinect_noise();
  std::vector<float> image(12, 0.0f);
  DepthPredictionParams p;
  p.rule = DepthPredictionRule::linear;
  expect_throw_naming<InvalidParameter>([&] { predict_depth(unknown_surface(4, 3), p); }, "linear");
  p.discontinuity_sigmas = 0.0;
  expect_throw_naming<InvalidParameter>([&] { predict_dense_depth(image, 4, 3, m, p); }, "discontinuity_sigmas");
  p.discontinuity_sigmas = std::numeric_limits<double>::quiet_NaN();
  expect_throw_naming<InvalidParameter>([&] { predict_dense_depth(image, 4, 3, m, p); }, "discontinuity_sigmas");
  p.discontinuity_sigmas = 6.0;
  p.radius_columns = -2;
  expect_throw_naming<InvalidParameter>([&] { predict_dense_depth(image, 4, 3, m, p); }, "radius_columns = -2");
  p.radius_columns = 16;
  p.rule = static_cast<DepthPredictionRule>(7);
  expect_throw_naming<InvalidParameter>([&] { predict_dense_depth(image, 4, 3, m, p); }, "rule");
  p.rule = DepthPredictionRule::linear;
  expect_throw_naming<InvalidParameter>([&] { predict_dense_depth({}, 0, 3, m, p); }, "width = 0");
  expect_throw_naming<InvalidInput>([&] { predict_dense_depth(image, 5, 3, m, p); }, "5 x 3");
  image[6] = -1.0f;
  expect_throw_naming<InvalidInput>([&] { predict_dense_depth(image, 4, 3, m, p); }, "pixel (2, 1)");
  image[6] = std::numeric_limits<float>::infinity();
  expect_throw_naming<InvalidInput>([&] { predict_dense_depth(image, 4, 3, m, p); }, "pixel (2, 1)");
  image[6] = -std::numeric_limits<float>::infinity();
  expect_throw_naming<InvalidInput>([&] { predict_dense_depth(image, 4, 3, m, p); }, "pixel (2, 1)");
  image[6] = -0.0f;  // zero: no sample
  EXPECT_NO_THROW(predict_dense_depth(image, 4, 3, m, p));
  image[6] = std::numeric_limits<float>::quiet_NaN();  // NaN: no sample, as 0
  const PredictedDepth none = predict_dense_depth(image, 4, 3, m, p);
  for (const std::int32_t d : none.distance) EXPECT_EQ(d, -1);
}

// Circumcircle test in double (exact for these small integer coordinates).
bool strictly_in_circumcircle(const SampleTriangulation& s, const std::array<std::int32_t, 3>& t, int px, int py) {
  double m[3][3];
  for (int i = 0; i < 3; ++i) {
    const double dx = s.x(t[static_cast<std::size_t>(i)]) - px, dy = s.y(t[static_cast<std::size_t>(i)]) - py;
    m[i][0] = dx;
    m[i][1] = dy;
    m[i][2] = dx * dx + dy * dy;
  }
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return det > 0;
}

TEST(SampleTriangulation, IsDelaunayAndCoversTheHull) {
  const int w = 64, h = 48;
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    const SampleTriangulation s = triangulate_samples(sparse_plane(w, h, seed), w, h, kinect_noise());
    ASSERT_GT(s.vertex_count(), 100u);
    double area = 0;
    std::vector<int> used(s.vertex_count(), 0);
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
      ASSERT_GT(s.area_px2(t), 0.0) << t;  // counter-clockwise, never degenerate
      area += s.area_px2(t);
      for (const std::int32_t v : s.triangles[t]) used[static_cast<std::size_t>(v)] = 1;
      for (std::size_t v = 0; v < s.vertex_count(); ++v)
        EXPECT_FALSE(strictly_in_circumcircle(s, s.triangles[t], s.x(static_cast<std::int32_t>(v)), s.y(static_cast<std::int32_t>(v))))
            << "triangle " << t << " holds vertex " << v;
    }
    EXPECT_DOUBLE_EQ(area, (w - 1) * (h - 1));  // the samples' hull is the image (its four corners are samples)
    EXPECT_EQ(std::count(used.begin(), used.end(), 1), static_cast<long>(s.vertex_count()));
    EXPECT_TRUE(std::is_sorted(s.vertex_column.begin(), s.vertex_column.end()));
  }
}

TEST(SampleTriangulation, GridOfSamplesAndTooFewSamples) {
  std::vector<float> image(9 * 7, 0.0f);
  for (int y = 0; y < 7; y += 2)
    for (int x = 0; x < 9; x += 2) image[static_cast<std::size_t>(y * 9 + x)] = 2.0f;  // 5 x 4, all co-circular
  const SampleTriangulation s = triangulate_samples(image, 9, 7, kinect_noise());
  EXPECT_EQ(s.triangles.size(), 2u * 4u * 3u);
  for (std::size_t t = 0; t < s.triangles.size(); ++t) EXPECT_DOUBLE_EQ(s.area_px2(t), 2.0);
  std::vector<float> line(9 * 7, 0.0f);
  for (int x = 0; x < 9; ++x) line[static_cast<std::size_t>(3 * 9 + x)] = 1.0f;  // collinear: no triangle
  EXPECT_TRUE(triangulate_samples(line, 9, 7, kinect_noise()).triangles.empty());
  EXPECT_TRUE(triangulate_samples(std::vector<float>(4, 0.0f), 2, 2, kinect_noise()).triangles.empty());
}

TEST(SampleTriangulation, NonPlanarityIsTheLeaveOneOutResidualInSigmas) {
  const int w = 64, h = 48;
  std::vector<float> image = sparse_plane(w, h, 11);
  // Lift one interior sample by 10 sigma from the plane.
  std::size_t bump = static_cast<std::size_t>(20 * w + 30);
  while (image[bump] == 0.0f) ++bump;
  const double z = image[bump];
  image[bump] = static_cast<float>(z + 10.0 * kinect_noise().sigma_depth_at(z));
  const SampleTriangulation s = triangulate_samples(image, w, h, kinect_noise());
  const auto v = static_cast<std::size_t>(std::find(s.vertex_column.begin(), s.vertex_column.end(), bump) - s.vertex_column.begin());
  ASSERT_LT(v, s.vertex_count());
  EXPECT_NEAR(s.residual_sigmas[v], 10.0, 0.01);  // sigma at the plane: exactly the lift
  for (std::size_t u = 0; u < s.vertex_count(); ++u) {
    if (u == v) continue;
    const bool neighbour = std::any_of(s.triangles.begin(), s.triangles.end(), [&](const auto& t) {
      return std::count(t.begin(), t.end(), static_cast<std::int32_t>(u)) && std::count(t.begin(), t.end(), static_cast<std::int32_t>(v));
    });
    if (!neighbour) {
      EXPECT_LT(s.residual_sigmas[u], 0.02) << u;  // on the plane, and its neighbours too
    }
  }
  const std::vector<std::size_t> top = top_scored_triangles(s, 3);
  ASSERT_EQ(top.size(), 3u);
  for (std::size_t k = 0; k < top.size(); ++k) {
    if (k > 0) {
      EXPECT_GE(s.score(top[k - 1]), s.score(top[k]));
    }
    EXPECT_GE(s.non_planarity_sigmas(top[k]), 1.0);
    const ColumnIndex c = s.centroid_column(top[k]);
    EXPECT_LT(c, static_cast<ColumnIndex>(w * h));
  }
  const SampleTriangulation flat = triangulate_samples(sparse_plane(w, h, 11), w, h, kinect_noise());
  EXPECT_LT(*std::max_element(flat.residual_sigmas.begin(), flat.residual_sigmas.end()), 0.02);
}


// The samples of `all` in batches 0..k of `batches`: batch 0 holds the border samples (the hull stays the
// image) and a share of the others; the rest go to batches by a hash of the pixel.
std::vector<float> first_batches(const std::vector<float>& all, int w, int h, int batches, int k) {
  std::vector<float> image(all.size(), 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto c = static_cast<std::size_t>(y * w + x);
      const bool border = x == 0 || y == 0 || x == w - 1 || y == h - 1;
      const int batch = border ? 0 : static_cast<int>((c * 2654435761u >> 7) % static_cast<std::size_t>(batches));
      if (batch <= k) image[c] = all[c];
    }
  return image;
}

std::size_t samples_in(const std::vector<float>& image) {
  return static_cast<std::size_t>(std::count_if(image.begin(), image.end(), [](float z) { return z > 0.0f; }));
}

// A triangle as its vertices' columns, starting from the smallest (the same triangle in any vertex order).
std::array<ColumnIndex, 3> column_triangle(const SampleTriangulation& s, std::size_t t) {
  std::array<ColumnIndex, 3> c{};
  for (int i = 0; i < 3; ++i) c[static_cast<std::size_t>(i)] = s.vertex_column[static_cast<std::size_t>(s.triangles[t][static_cast<std::size_t>(i)])];
  std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
  return c;
}

// The same vertices (depths, residuals) and triangles (flags) as from scratch, whatever the order of the
// vertices and triangles.
void expect_same_triangulation(const SampleTriangulation& s, const SampleTriangulation& scratch) {
  ASSERT_EQ(s.vertex_count(), scratch.vertex_count());
  std::map<ColumnIndex, std::pair<float, float>> vertex;  // column -> (depth, residual)
  for (std::size_t v = 0; v < scratch.vertex_count(); ++v)
    vertex[scratch.vertex_column[v]] = {scratch.vertex_depth_m[v], scratch.residual_sigmas[v]};
  for (std::size_t v = 0; v < s.vertex_count(); ++v) {
    const auto& [depth, residual] = vertex.at(s.vertex_column[v]);
    EXPECT_EQ(s.vertex_depth_m[v], depth) << v;
    EXPECT_EQ(s.residual_sigmas[v], residual) << v;
  }
  ASSERT_EQ(s.triangles.size(), scratch.triangles.size());
  std::map<std::array<ColumnIndex, 3>, std::uint8_t> flag;
  for (std::size_t t = 0; t < scratch.triangles.size(); ++t) flag[column_triangle(scratch, t)] = scratch.interpolable[t];
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    const auto it = flag.find(column_triangle(s, t));
    ASSERT_NE(it, flag.end()) << t;
    EXPECT_EQ(s.interpolable[t], it->second) << t;
  }
}

// The same, in the same order.
void expect_identical(const SampleTriangulation& a, const SampleTriangulation& b) {
  EXPECT_EQ(a.vertex_column, b.vertex_column);
  EXPECT_EQ(a.triangles, b.triangles);
  expect_same_triangulation(a, b);
}

TEST(SampleTriangulator, GrowsByInsertionAndStaysTheDelaunayTriangulationOfItsSamples) {
  const int w = 64, h = 48, batches = 4;
  for (std::uint32_t seed = 1; seed <= 6; ++seed) {
    std::vector<float> all = sparse_plane(w, h, seed);
    // One interior sample of the last batch is lifted 10 sigma off the plane: its neighbours' residuals
    // must follow it when it arrives.
    std::size_t bump = static_cast<std::size_t>(24 * w + 30);
    while (!(all[bump] > 0.0f && first_batches(all, w, h, batches, batches - 2)[bump] == 0.0f)) ++bump;
    all[bump] = static_cast<float>(all[bump] + 10.0 * kinect_noise().sigma_depth_at(all[bump]));
    SampleTriangulator incremental;
    for (int k = 0; k < batches; ++k) {
      std::vector<float> image = first_batches(all, w, h, batches, k);
      // Depths change from update to update (fused measurements): a plane in inverse depth stays one.
      for (float& z : image) z = z > 0.0f ? static_cast<float>(z / (1.0 + 0.01 * k)) : 0.0f;
      const SampleTriangulation& s = incremental.update(image, w, h, kinect_noise());
      const SampleTriangulation scratch = triangulate_samples(image, w, h, kinect_noise());
      EXPECT_EQ(incremental.started_over_last(), k == 0);
      EXPECT_EQ(incremental.inserted_last(), k == 0 ? samples_in(image) : samples_in(image) - samples_in(first_batches(all, w, h, batches, k - 1)));
      if (k == 0) {
        expect_identical(s, scratch);
        continue;
      }
      // The same samples at their current depths, triangulated: Delaunay, covering the hull, as many triangles.
      ASSERT_EQ(s.vertex_count(), scratch.vertex_count());
      for (std::size_t v = 0; v < s.vertex_count(); ++v) ASSERT_EQ(s.vertex_depth_m[v], image[s.vertex_column[v]]) << v;
      ASSERT_EQ(s.triangles.size(), scratch.triangles.size()) << "seed " << seed << " batch " << k;
      double area = 0;
      for (std::size_t t = 0; t < s.triangles.size(); ++t) {
        ASSERT_GT(s.area_px2(t), 0.0);
        area += s.area_px2(t);
        for (std::size_t v = 0; v < s.vertex_count(); ++v)
          ASSERT_FALSE(strictly_in_circumcircle(s, s.triangles[t], s.x(static_cast<std::int32_t>(v)), s.y(static_cast<std::int32_t>(v))))
              << "seed " << seed << " batch " << k << " triangle " << t << " holds vertex " << v;
      }
      EXPECT_DOUBLE_EQ(area, (w - 1) * (h - 1));
      // The same triangles (co-circular samples are decided by a fixed rule, not by their order), and the
      // same residuals and flags at the current depths.
      expect_same_triangulation(s, scratch);
      if (k == batches - 1) {
        const auto v = static_cast<std::size_t>(std::find(s.vertex_column.begin(), s.vertex_column.end(), bump) - s.vertex_column.begin());
        ASSERT_LT(v, s.vertex_count());
        EXPECT_NEAR(s.residual_sigmas[v], 10.0 * (1.0 + 0.01 * k), 0.05);  // depths / (1 + 0.01 k), sigma ~ z^2
      }
    }
  }
}

// A few new samples and a few changed depths: only their neighbourhoods' residuals are recomputed
// (walking around each vertex), and they are those of the triangulation from scratch.
TEST(SampleTriangulator, AFewNewSamplesAndDepthsRecomputeTheirNeighbourhoodAsFromScratch) {
  const int w = 64, h = 48;
  std::vector<float> all = sparse_plane(w, h, 5);
  std::vector<std::size_t> interior;
  for (int y = 2; y < h - 2; ++y)
    for (int x = 2; x < w - 2; ++x)
      if (all[static_cast<std::size_t>(y * w + x)] > 0.0f) interior.push_back(static_cast<std::size_t>(y * w + x));
  ASSERT_GT(interior.size(), 60u);
  std::vector<float> before = all;
  for (std::size_t k = 0; k < 5; ++k) before[interior[k * 11]] = 0.0f;  // five samples arrive later
  SampleTriangulator t;
  t.update(before, w, h, kinect_noise());
  for (std::size_t k = 0; k < 6; ++k) all[interior[k * 7 + 3]] *= 1.0f + 0.004f * static_cast<float>(k + 1);  // six move
  const SampleTriangulation& s = t.update(all, w, h, kinect_noise());
  EXPECT_FALSE(t.started_over_last());
  EXPECT_EQ(t.inserted_last(), 5u);
  expect_same_triangulation(s, triangulate_samples(all, w, h, kinect_noise()));
  // Another model's depth noise: every residual is in its sigmas.
  SensorModelParams other = kinect_noise().params();
  other.sigma_depth_per_m2 *= 2.0;
  expect_same_triangulation(t.update(all, w, h, SensorModel(other)), triangulate_samples(all, w, h, SensorModel(other)));
  EXPECT_EQ(t.updates(), 3u);
  EXPECT_EQ(t.start_overs(), 1u);
}

// Samples that stop being samples (their surface fell below the sample rule) are removed: one at a time
// or many, on the hull and inside, together with new samples and changed depths; every update equals the
// triangulation from scratch, and none starts over.
TEST(SampleTriangulator, LostSamplesAreRemovedAsIfNeverInserted) {
  const int w = 64, h = 48;
  for (std::uint32_t seed = 1; seed <= 6; ++seed) {
    std::vector<float> image = sparse_plane(w, h, seed);
    std::mt19937 rng(seed);
    SampleTriangulator t;
    t.update(image, w, h, kinect_noise());
    for (int round = 0; round < 8; ++round) {
      std::vector<std::size_t> samples;
      for (std::size_t c = 0; c < image.size(); ++c)
        if (image[c] > 0.0f) samples.push_back(c);
      std::shuffle(samples.begin(), samples.end(), rng);
      const std::size_t lose = round % 2 == 0 ? 1 : 1 + rng() % 25;  // the hull's too: the border rows
      for (std::size_t k = 0; k < lose; ++k) image[samples[k]] = 0.0f;
      if (round % 3 == 2) {
        for (std::size_t k = lose; k < lose + 5; ++k) image[samples[k]] *= 1.01f;  // depths move
        for (int k = 0; k < 7; ++k) image[rng() % image.size()] = 1.5f;              // samples arrive
      }
      std::vector<ColumnIndex> kept;  // the vertices still samples, in their order
      for (const ColumnIndex c : t.triangulation().vertex_column)
        if (image[c] > 0.0f) kept.push_back(c);
      const std::size_t lost = t.triangulation().vertex_count() - kept.size();  // an arrival may refill one
      ASSERT_GE(lost, lose > 7 ? lose - 7 : 1u);
      const SampleTriangulation& s = t.update(image, w, h, kinect_noise());
      ASSERT_FALSE(t.started_over_last()) << "seed " << seed << " round " << round;
      EXPECT_EQ(t.removed_last(), lost);
      expect_same_triangulation(s, triangulate_samples(image, w, h, kinect_noise()));
      EXPECT_TRUE(std::equal(kept.begin(), kept.end(), s.vertex_column.begin()));  // order kept, new ones after
    }
  }
}

TEST(SampleTriangulator, StartsOverWhenTheSizeChangesOrAnUpdateWasInterrupted) {
  const int w = 64, h = 48;
  const std::vector<float> all = sparse_plane(w, h, 3);
  SampleTriangulator t;
  t.update(first_batches(all, w, h, 2, 0), w, h, kinect_noise());
  t.update(all, w, h, kinect_noise());
  EXPECT_FALSE(t.started_over_last());
  // Bad input throws before anything changes.
  std::vector<float> bad = all;
  bad[5] = -1.0f;
  EXPECT_THROW(t.update(bad, w, h, kinect_noise()), InvalidInput);
  expect_same_triangulation(t.triangulation(), triangulate_samples(all, w, h, kinect_noise()));
  // Another size.
  const std::vector<float> small = sparse_plane(32, 24, 4);
  expect_identical(t.update(small, 32, 24, kinect_noise()), triangulate_samples(small, 32, 24, kinect_noise()));
  EXPECT_TRUE(t.started_over_last());
  // An update stopped by a cancel leaves nothing half-inserted: the next one starts over.
  request_stop(2);
  EXPECT_THROW(t.update(all, w, h, kinect_noise()), Cancelled);
  clear_stop_request();
  EXPECT_TRUE(t.triangulation().triangles.empty());
  expect_identical(t.update(all, w, h, kinect_noise()), triangulate_samples(all, w, h, kinect_noise()));
  EXPECT_TRUE(t.started_over_last());
}

}  // namespace
}  // namespace occ_improve
