// 16-bit depth PGM (read_depth_image16: header, size checks, byte-order guess).
#include "fuzz_target.hpp"
#include "occ_improve/io/depth_image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return occ_improve::fuzz::parse_as_file(data, size, ".pgm",
                                          [](const std::string& path) { occ_improve::read_depth_image16(path); });
}
