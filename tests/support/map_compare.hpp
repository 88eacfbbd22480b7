#pragma once
// Exact comparisons of grids and of the maps computed from them, for the map_io tests (generated scenes
// in tests/test_map_io.cpp, real frames in tests/pcl/test_map_io_real.cpp).
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/sensor/sensor_model.hpp"
#include "occ_improve/maps/surface.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace occ_improve::test {

inline bool same_params(const GeometryParams& a, const GeometryParams& b) {
  return a.azimuth_bins == b.azimuth_bins && a.elevation_bins == b.elevation_bins && a.depth_bins == b.depth_bins &&
         a.azimuth_min_rad == b.azimuth_min_rad && a.azimuth_max_rad == b.azimuth_max_rad &&
         a.elevation_min_rad == b.elevation_min_rad && a.elevation_max_rad == b.elevation_max_rad &&
         a.depth_binning == b.depth_binning && a.depth_min_m == b.depth_min_m && a.depth_max_m == b.depth_max_m;
}

inline bool same_model(const SensorModelParams& a, const SensorModelParams& b) {
  return a.sigma_azimuth_rad == b.sigma_azimuth_rad && a.sigma_elevation_rad == b.sigma_elevation_rad &&
         a.sigma_depth_m == b.sigma_depth_m && a.sigma_depth_per_m2 == b.sigma_depth_per_m2 &&
         a.sigma_depth_floor_m == b.sigma_depth_floor_m && a.support_k == b.support_k;
}

/// Two float arrays (std::vector, ColumnWindow) of the same size and bit patterns.
template <typename Floats>
bool same_bits(const Floats& a, const Floats& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

/// Every column bit for bit: the same touched set, runs, windows and float bit patterns; same options.
inline void expect_identical(const ColumnGrid& a, const ColumnGrid& b) {
  ASSERT_TRUE(same_params(a.geometry().params(), b.geometry().params()));
  EXPECT_EQ(a.options().mode, b.options().mode);
  EXPECT_EQ(a.options().probability_min, b.options().probability_min);
  EXPECT_EQ(a.options().probability_max, b.options().probability_max);
  EXPECT_EQ(a.options().memory_cap_bytes, b.options().memory_cap_bytes);
  std::size_t differing = 0;
  for (std::size_t c = 0; c < a.geometry().column_count(); ++c) {
    const ColumnData* x = a.find(static_cast<ColumnIndex>(c));
    const ColumnData* y = b.find(static_cast<ColumnIndex>(c));
    const bool tx = x && x->touched(), ty = y && y->touched();
    if (tx != ty) {
      ++differing;
      continue;
    }
    if (!tx) continue;
    const bool same = x->uniform_end == y->uniform_end &&
                      (x->uniform_end == 0 || std::memcmp(&x->uniform_value, &y->uniform_value, sizeof(float)) == 0) &&
                      same_bits(x->window, y->window);
    differing += same ? 0 : 1;
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_EQ(a.touched_column_count(), b.touched_column_count());
  EXPECT_EQ(a.stored_voxel_count(), b.stored_voxel_count());
}

inline void expect_same_surface(const SurfaceMap& a, const SurfaceMap& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.bin, b.bin);
  EXPECT_EQ(a.unknown, b.unknown);
  EXPECT_TRUE(same_bits(a.depth_m, b.depth_m));
  EXPECT_TRUE(same_bits(a.probability, b.probability));
}

inline void expect_same_improvement(const ImprovementMap& a, const ImprovementMap& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_TRUE(same_bits(a.value, b.value));
}

}  // namespace occ_improve::test
