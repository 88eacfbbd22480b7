#pragma once
// Private to pcl_tools/src: the characters a PCD or PLY header line may hold before PCL reads the file.
#include "occ_improve/errors.hpp"

#include <exception>
#include <new>
#include <string>

namespace occ_improve::detail {

/// Why a header line is refused, or nullptr: `binary` (the format's words for it) for a byte outside
/// printable ASCII and \t \n \r (the data began early, or not a text header); a vertical tab or form
/// feed otherwise. Our header checks split lines at any white space, PCL 1.13's readers at spaces, tabs
/// and CRs only: "DATA<VT>ascii" is one word to them, and PCL's PCD reader then threw std::out_of_range,
/// its PLY reader failed an assertion (abort) on "<FF>obj_info" (both found by make fuzz). Such lines are
/// refused, so that both read the words the checks read.
inline const char* refused_header_line(const std::string& line, const char* binary) {
  bool vertical_space = false;
  for (const unsigned char ch : line) {
    if (ch < 9 || (ch > 13 && ch < 32) || ch > 126) return binary;
    vertical_space = vertical_space || ch == '\v' || ch == '\f';
  }
  return vertical_space ? "a header line holds a vertical tab or form feed (PCL cannot read it)" : nullptr;
}

/// PCL's read() on a file the header checks passed: a failed status, or an exception it throws (out of
/// memory stays itself), becomes a FormatError naming the file.
template <typename Read>
void read_or_throw(const std::string& path, const char* format, Read&& read) {
  const std::string unreadable = "'" + path + "' is not a readable " + format + " file";
  int status = 0;
  try {
    status = read();
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    throw FormatError(unreadable + " (PCL's reader: " + e.what() + ")");
  }
  if (status < 0) throw FormatError(unreadable);
}

}  // namespace occ_improve::detail
