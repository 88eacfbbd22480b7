#pragma once
// What every fuzz target shares. The parsers read files, so each input is written to a file of this
// process's own (the right extension, since the readers dispatch on it) and parsed from there. A typed
// occ_improve::Error is the expected refusal of a bad file; anything else escaping (std::bad_alloc, a PCL
// exception, a crash, a hang) is a finding.
#include "occ_improve/errors.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace occ_improve::fuzz {

/// `data` written to a per-process file named "occ_fuzz_<pid><extension>" in /tmp; returns its path.
inline std::string as_file(const std::uint8_t* data, std::size_t size, const char* extension) {
  const std::string path = "/tmp/occ_fuzz_" + std::to_string(::getpid()) + extension;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return path;  // the parser then reports an unreadable file, which is fine
  if (size) std::fwrite(data, 1, size, f);
  std::fclose(f);
  return path;
}

/// Runs `parse` on `data` as a file; typed refusals are swallowed, anything else propagates.
template <typename Parse>
int parse_as_file(const std::uint8_t* data, std::size_t size, const char* extension, Parse parse) {
  const std::string path = as_file(data, size, extension);
  try {
    parse(path);
  } catch (const occ_improve::Error&) {
  }
  std::remove(path.c_str());
  return 0;
}

}  // namespace occ_improve::fuzz
