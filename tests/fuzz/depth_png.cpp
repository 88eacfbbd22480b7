// 16-bit depth PNG (read_depth_image16: our size checks, then libpng).
#include "fuzz_target.hpp"
#include "occ_improve/io/depth_image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return occ_improve::fuzz::parse_as_file(data, size, ".png",
                                          [](const std::string& path) { occ_improve::read_depth_image16(path); });
}
