// Maps one frame, saves the map, and resumes mapping from the saved file in a "later session": the
// resumed mapper continues exactly where the first one stopped (map_io.hpp, docs/MAP_FORMAT.md).
//   example_save_resume [MAP_FILE]     (default: sample.occmap in the current folder)
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sample_scene.hpp"

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <numeric>
#include <string>

namespace {
double total_improvement(const occ_improve::ImprovementMap& map) {
  return std::accumulate(map.value.begin(), map.value.end(), 0.0);
}
}  // namespace

int main(int argc, char** argv) {
  using namespace occ_improve;
  const std::string path = argc > 1 ? argv[1] : "sample.occmap";
  try {
    const auto frames = sample::generate_sequence(2);

    // First session: one frame, then save.
    Mapper first(kinect_v1_paper());
    first.insert(PointSpan::from(frames[0].points()));
    auto start = std::chrono::steady_clock::now();
    save_map(path, first.grid(), first.model().params());
    const double save_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("saved %s: %.1f MB in %.0f ms, total improvement %.1f\n", path.c_str(),
                static_cast<double>(std::filesystem::file_size(path)) / 1e6, save_s * 1e3,
                total_improvement(first.improvement()));

    // Later session: load, rebuild surface and improvement, insert the next frame.
    start = std::chrono::steady_clock::now();
    LoadedMap loaded = load_map(path);
    const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    Mapper resumed(std::move(loaded.grid), SensorModel(loaded.model));
    std::printf("loaded in %.0f ms, total improvement %.1f (same map)\n", load_s * 1e3,
                total_improvement(resumed.improvement()));
    resumed.insert(PointSpan::from(frames[1].points()));
    std::printf("after the second frame: total improvement %.1f\n", total_improvement(resumed.improvement()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
