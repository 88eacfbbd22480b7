// predict_depth: nearest sample in chessboard distance within a radius.
#include "occ_improve/depth_prediction.hpp"
#include "occ_improve/errors.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace occ_improve
