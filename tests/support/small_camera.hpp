#pragma once
// A small pinhole camera (64 x 48 pixels, principal point at the centre) for unit tests that need a
// pixel-native grid but not a full Kinect frame.
#include "occ_improve/geometry/geometry.hpp"

namespace occ_improve::test {

inline PinholeIntrinsics small_camera() {
  PinholeIntrinsics k;
  k.width = 64;
  k.height = 48;
  k.fx = k.fy = 60;
  k.cx = 31.5;
  k.cy = 23.5;
  return k;
}

}  // namespace occ_improve::test
