// TIFF: read_depth_image16 (size checks, libtiff's strips) and the colour reader (libtiff's RGBA interface)
// on the same input, as a `*_depth.tiff` and the `*_rgb.tiff` beside it are read.
#include "fuzz_target.hpp"
#include "occ_improve/io/depth_image.hpp"
#include "occ_improve/io/tiff.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  occ_improve::fuzz::parse_as_file(data, size, ".tiff", [](const std::string& path) { occ_improve::read_depth_image16(path); });
  return occ_improve::fuzz::parse_as_file(data, size, ".tiff",
                                          [](const std::string& path) { occ_improve::read_tiff_rgb8(path); });
}
