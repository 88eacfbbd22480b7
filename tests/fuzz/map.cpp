// Saved map (load_map) under a caller's cap of 256 MiB, so a forged geometry must be refused, not built.
#include "fuzz_target.hpp"
#include "occ_improve/io/map_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return occ_improve::fuzz::parse_as_file(data, size, ".occmap", [](const std::string& path) {
    occ_improve::load_map(path, std::size_t{256} << 20);
  });
}
