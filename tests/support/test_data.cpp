#include "support/test_data.hpp"

#include <cstdlib>
#include <filesystem>

namespace occ_improve::test {

std::string data_dir() {
  const char* env = std::getenv("OCC_IMPROVE_DATA_DIR");
  const std::string dir = env && *env ? env : OCC_IMPROVE_DATA_DIR_DEFAULT;
  std::error_code ec;
  return std::filesystem::is_directory(dir, ec) ? dir : std::string();
}

std::string data_file(const std::string& relative) {
  const std::string dir = data_dir();
  if (dir.empty()) return {};
  const std::string path = dir + "/" + relative;
  std::error_code ec;
  return std::filesystem::exists(path, ec) ? path : std::string();
}

}  // namespace occ_improve::test
