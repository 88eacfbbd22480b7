// 4x4 pose text file (read_pose_matrix_file: 7-Scenes / 3DMatch *.pose.txt).
#include "fuzz_target.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return occ_improve::fuzz::parse_as_file(data, size, ".pose.txt",
                                          [](const std::string& path) { occ_improve::read_pose_matrix_file(path); });
}
