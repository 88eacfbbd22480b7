// PLY: our header validation, then PCL's PLYReader, its result's check and the conversion (load_ply_frame).
#include "fuzz_target.hpp"
#include "occ_improve/pcl/frame_io.hpp"

#include <pcl/console/print.h>

// PCL's warnings and errors about each malformed body would cost more than the parse.
static const bool quiet_pcl = (pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS), true);

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return occ_improve::fuzz::parse_as_file(data, size, ".ply",
                                          [](const std::string& path) { occ_improve::load_ply_frame(path); });
}
