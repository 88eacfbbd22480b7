// The virtual selective sensor: requested rays only, Kinect noise and quantisation, deterministic.
#include "occ_improve/errors.hpp"
#include "occ_improve/sim/virtual_sensor.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

namespace occ_improve {
namespace {

VirtualSensor flat_wall(double z, const VirtualSensorParams& params = {}) {
  PinholeIntrinsics k;  // 640 x 480, fx = 525
  std::vector<float> depth(640u * 480u, static_cast<float>(z));
  depth[0] = 0.0f;                                    // no return
  depth[1] = std::numeric_limits<float>::quiet_NaN();  // no return
  return VirtualSensor(depth, k, params);
}

TEST(VirtualSensor, ReturnsOnlyWhatWasAskedWithKinectNoise) {
  VirtualSensor s = flat_wall(2.0);
  std::vector<std::uint32_t> pixels;
  for (std::uint32_t p = 0; p < 20000; ++p) pixels.push_back(p * 13 + 2);
  const auto d = s.shoot(pixels);
  ASSERT_EQ(d.size(), pixels.size());
  double sum = 0, sum2 = 0;
  std::set<float> levels;
  for (float z : d) {
    sum += z;
    sum2 += (z - 2.0) * (z - 2.0);
    levels.insert(z);
  }
  EXPECT_NEAR(sum / d.size(), 2.0, 1e-3);
  const double step = 2.0 * 2.0 * 0.125 / (525.0 * 0.075);  // 12.7 mm at 2 m (11.4 mm with fx = 585)
  EXPECT_NEAR(std::sqrt(sum2 / d.size()), std::hypot(1.425e-3 * 4, step / std::sqrt(12.0)), 1.5e-3);
  // Disparity quantisation: adjacent levels z^2 step / (f b) apart.
  std::vector<float> sorted(levels.begin(), levels.end());
  const auto mid = std::lower_bound(sorted.begin(), sorted.end(), 2.0f);
  EXPECT_NEAR(*mid - *(mid - 1), step, 0.0008);
  EXPECT_EQ(s.shots_taken(), 1u);
  EXPECT_EQ(s.shoot({0, 1})[0], 0.0f);
  EXPECT_EQ(s.points({0, 1, 2}, s.shoot({0, 1, 2})).size(), 1u);
}

// The rays of a shot that returned, as the return record takes them: the two silent pixels (0 and NaN
// in the scene) and no others.
TEST(VirtualSensor, ReturnedMarksTheRaysWithADepth) {
  VirtualSensor s = flat_wall(2.0);
  EXPECT_EQ(VirtualSensor::returned(s.shoot({0, 1, 2, 3})), (std::vector<std::uint8_t>{0, 0, 1, 1}));
  EXPECT_TRUE(VirtualSensor::returned({}).empty());
}

TEST(VirtualSensor, SeededAndIndependentOfTheOrderAsked) {
  VirtualSensor a = flat_wall(1.5), b = flat_wall(1.5);
  const auto da = a.shoot({10, 20, 30});
  const auto db = b.shoot({30, 10, 20});
  EXPECT_EQ(da[0], db[1]);
  EXPECT_EQ(da[2], db[0]);
  VirtualSensorParams other;
  other.seed = 7;
  VirtualSensor c = flat_wall(1.5, other);
  int same = 0;
  const auto dc = c.shoot({10, 20, 30});
  for (int i = 0; i < 3; ++i) same += dc[static_cast<std::size_t>(i)] == da[static_cast<std::size_t>(i)];
  EXPECT_LT(same, 3);
  std::vector<std::uint32_t> many(1000);
  for (std::uint32_t i = 0; i < 1000; ++i) many[i] = 1000 + i;
  const auto first = a.shoot(many), second = a.shoot(many);  // new noise per shot
  int repeated = 0;
  for (std::size_t i = 0; i < many.size(); ++i) repeated += first[i] == second[i];
  EXPECT_LT(repeated, 700);
}

TEST(VirtualSensor, BadInputThrowsAndCountsNoShot) {
  VirtualSensor s = flat_wall(2.0);
  try {
    s.shoot({5, 640u * 480u});
    FAIL() << "no throw";
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("shot pixel = 307200"), std::string::npos);
  }
  EXPECT_EQ(s.shots_taken(), 0u);
  EXPECT_THROW(VirtualSensor(std::vector<float>(10, 1.0f), PinholeIntrinsics{}), InvalidInput);
  VirtualSensorParams bad;
  bad.baseline_m = 0;
  EXPECT_THROW(flat_wall(2.0, bad), InvalidParameter);
}

}  // namespace
}  // namespace occ_improve
