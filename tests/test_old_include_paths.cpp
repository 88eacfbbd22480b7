// The include paths before the stage folders (0.1) still compile for one release: each forwards to
// its new home (CHANGELOG.md). This file includes only old paths; a forwarding header that went
// missing or pointed nowhere fails the build, and the types below must be the new ones.
#include "occ_improve/atomic_file.hpp"
#include "occ_improve/depth_prediction.hpp"
#include "occ_improve/geometry.hpp"
#include "occ_improve/grid.hpp"
#include "occ_improve/improvement.hpp"
#include "occ_improve/integrate.hpp"
#include "occ_improve/intrinsics_fit.hpp"
#include "occ_improve/map_io.hpp"
#include "occ_improve/mask.hpp"
#include "occ_improve/multiscale.hpp"
#include "occ_improve/planner.hpp"
#include "occ_improve/presets.hpp"
#include "occ_improve/ranking.hpp"
#include "occ_improve/render.hpp"
#include "occ_improve/return_model.hpp"
#include "occ_improve/sample_triangulation.hpp"
#include "occ_improve/segmentation.hpp"
#include "occ_improve/sensor_model.hpp"
#include "occ_improve/surface.hpp"
#include "occ_improve/virtual_sensor.hpp"

#include <gtest/gtest.h>

namespace occ_improve {

TEST(OldIncludePaths, ForwardToTheStageHeaders) {
  const SensorPreset preset = kinect_v1(PinholeIntrinsics{});
  const GridGeometry geometry(preset.geometry);
  EXPECT_EQ(geometry.width(), 640);
  EXPECT_EQ(geometry.height(), 480);
}

}  // namespace occ_improve
