#pragma once
// Whole files as bytes, and the message of the FormatError a call throws: what the reader and tool tests
// write, read back and expect.
#include "occ_improve/errors.hpp"

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>

namespace occ_improve::test {

/// The whole of a file (empty when it cannot be read).
inline std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/// The message of the FormatError `f` throws, or "no FormatError".
inline std::string format_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const FormatError& e) {
    return e.what();
  }
  return "no FormatError";
}

}  // namespace occ_improve::test
