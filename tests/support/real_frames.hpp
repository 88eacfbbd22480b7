#pragma once
// The five real frames the real-data tests share (one per dataset of ../shared/data), and how each is
// loaded with its camera: the dataset's intrinsics file, or intrinsics fitted to the organized PCD.
#include "occ_improve/sensor/intrinsics_fit.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "support/test_data.hpp"

#include <string>

namespace occ_improve::test {

struct RealFrame {
  std::string relative, intrinsics_file;
};

inline const RealFrame kRealFrames[] = {
    {"kinect/pcl_tutorials/pairwise/capture0001.pcd", ""},
    {"kinect/pcl_test/office1.pcd", ""},
    {"kinect/pcl_test/five_people.pcd", ""},
    {"segmentation/mosd_learn/learn0.pcd", ""},
    {"sequences/7scenes_redkitchen/frames/frame-000150.depth.png", "sequences/7scenes_redkitchen/camera-intrinsics.txt"},
};

/// The frame at `path` (f's file in the data folder) and its camera.
inline LoadedFrame load_with_camera(const RealFrame& f, const std::string& path) {
  if (!f.intrinsics_file.empty())
    return load_depth_frame(path, read_intrinsics_file(data_file(f.intrinsics_file)), DepthEncoding::millimetres);
  LoadedFrame frame = load_pcd_frame(path);
  frame.intrinsics = estimate_intrinsics(frame.cloud);
  return frame;
}

}  // namespace occ_improve::test
