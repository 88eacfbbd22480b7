#include "occ_improve/atomic_file.hpp"

#include "occ_improve/errors.hpp"

#include <atomic>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace occ_improve {
namespace {

std::string temporary_name(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  std::random_device random;
  std::ostringstream name;
  name << path << ".partial-" << std::hex << random() << '-' << counter++;
  return name.str();
}

}  // namespace

void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<bool(std::ostream&)>& write) {
  const std::string temporary = temporary_name(path);
  bool written = false;
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError("cannot create '" + temporary + "' to write " + what + " '" + path + "'");
    written = write(out);
    out.close();
    written = written && static_cast<bool>(out);
  }
  std::error_code error;
  if (written) std::filesystem::rename(temporary, path, error);
  if (!written || error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw IoError("cannot write " + what + " '" + path + "'" +
                  (error ? ": " + error.message() : std::string(" (disk full?)")));
  }
}

}  // namespace occ_improve
