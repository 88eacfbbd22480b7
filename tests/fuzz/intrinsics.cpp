// Intrinsics text file (read_intrinsics_file: "fx fy cx cy [w h]" or a 3x3 matrix).
#include "fuzz_target.hpp"
#include "occ_improve/pcl/frame_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return occ_improve::fuzz::parse_as_file(data, size, ".txt",
                                          [](const std::string& path) { occ_improve::read_intrinsics_file(path); });
}
