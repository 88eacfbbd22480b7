#pragma once
// Inputs shared by the benchmarks: the generated sample frame and the real frames in ../shared/data,
// found through OCC_IMPROVE_DATA_DIR (environment), else the folder configured at build time.
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sensor/intrinsics_fit.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sample_scene.hpp"

#include <Eigen/Core>
#include <benchmark/benchmark.h>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#if OCC_IMPROVE_BENCH_WITH_PCL
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#endif

namespace occ_improve::bench {

/// Full path of a file under the data folder, "" when it is absent.
inline std::string data_file(const std::string& relative) {
  const char* env = std::getenv("OCC_IMPROVE_DATA_DIR");
#ifdef OCC_IMPROVE_DATA_DIR_DEFAULT
  const std::string dir = env && *env ? env : OCC_IMPROVE_DATA_DIR_DEFAULT;
#else
  const std::string dir = env && *env ? env : "";
#endif
  if (dir.empty()) return "";
  const std::string path = dir + "/" + relative;
  return std::ifstream(path).good() ? path : "";
}

/// The generated sample frame as points (NaN where there is no return), built once.
inline const std::vector<Eigen::Vector3f>& sample_points() {
  static const std::vector<Eigen::Vector3f> points = sample::generate_scene().points();
  return points;
}

/// A real Kinect frame as packed xyz points; `error` says why it is empty.
inline std::vector<Eigen::Vector3f> load_pcd_points(const std::string& relative, std::string& error) {
  std::vector<Eigen::Vector3f> points;
#if OCC_IMPROVE_BENCH_WITH_PCL
  const std::string path = data_file(relative);
  if (path.empty()) {
    error = "real data '" + relative + "' not found (set OCC_IMPROVE_DATA_DIR to the shared/data folder)";
    return points;
  }
  pcl::PointCloud<pcl::PointXYZ> cloud;
  if (pcl::io::loadPCDFile(path, cloud) != 0) {
    error = "cannot read " + path;
    return points;
  }
  points.reserve(cloud.size());
  for (const auto& p : cloud.points) points.emplace_back(p.x, p.y, p.z);
#else
  error = "built without PCL: cannot read '" + relative + "'";
#endif
  return points;
}

/// The real frame of the insertion benchmarks (PCL tutorial capture, 640 x 480 organized), loaded once.
inline const std::vector<Eigen::Vector3f>& real_points(std::string& error) {
  static std::string load_error;
  static const std::vector<Eigen::Vector3f> points =
      load_pcd_points("kinect/pcl_tutorials/pairwise/capture0001.pcd", load_error);
  error = load_error;
  return points;
}

/// The frame a benchmark runs on: the generated sample, or the real capture (skips with the reason when
/// the data folder is absent).
enum class Input { sample, real };

inline const std::vector<Eigen::Vector3f>* input_points(Input input, benchmark::State& state) {
  if (input == Input::sample) return &sample_points();
  std::string error;
  const auto& points = real_points(error);
  if (points.empty()) {
    state.SkipWithError(error.c_str());
    return nullptr;
  }
  return &points;
}

/// The presets a benchmark compares (its last argument): the real-use default and the paper's.
enum PresetArg : int { kRealUse = 0, kPaper = 1 };

/// kinect_v1 with the input's own camera (the sample's intrinsics, or those fitted to the real frame's
/// 640 x 480 organized points), or kinect_v1_paper.
inline SensorPreset input_preset(Input input, int preset_arg) {
  if (preset_arg == kPaper) return kinect_v1_paper();
  if (input == Input::sample) return kinect_v1(sample::generate_scene().intrinsics);
  std::string error;
  const auto& points = real_points(error);
  return kinect_v1(fit_intrinsics(points.front().data(), 640, 480, 3).intrinsics);
}

inline const char* preset_label(int preset_arg) { return preset_arg == kPaper ? "kinect_v1_paper" : "kinect_v1"; }

}  // namespace occ_improve::bench
