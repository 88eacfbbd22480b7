// PCD: our header validation, then PCL's reader and the conversion to points (load_pcd_frame).
#include "fuzz_target.hpp"
#include "occ_improve/pcl/frame_io.hpp"

#include <pcl/console/print.h>

// PCL's warnings about each malformed body would cost more than the parse.
static const bool quiet_pcl = (pcl::console::setVerbosityLevel(pcl::console::L_ERROR), true);

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return occ_improve::fuzz::parse_as_file(data, size, ".pcd",
                                          [](const std::string& path) { occ_improve::load_pcd_frame(path); });
}
