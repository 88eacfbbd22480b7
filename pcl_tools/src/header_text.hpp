#pragma once
// Private to pcl_tools/src: the characters a PCD or PLY header line may hold before PCL reads the file.
#include "occ_improve/errors.hpp"

#include <exception>
#include <new>
#include <string>

namespace occ_improve::detail {

enum class HeaderText { plain, binary, vertical_space };

/// binary: a byte outside printable ASCII and \t \n \r (the data began early, or not a text header);
/// vertical_space: a vertical tab or form feed. Our header checks split lines at any white space, PCL
/// 1.13's readers at spaces, tabs and CRs only: "DATA<VT>ascii" is one word to them, and PCL's PCD reader
/// then threw std::out_of_range, its PLY reader failed an assertion (abort) on "<FF>obj_info" (both
/// found by make fuzz). Such lines are refused, so that both read the words the checks read.
inline HeaderText classify_header_line(const std::string& line) {
  HeaderText worst = HeaderText::plain;
  for (const unsigned char ch : line) {
    if (ch < 9 || (ch > 13 && ch < 32) || ch > 126) return HeaderText::binary;
    if (ch == '\v' || ch == '\f') worst = HeaderText::vertical_space;
  }
  return worst;
}

/// PCL's read(), with an exception it throws on a file the header checks passed turned into a
/// FormatError naming the file (out of memory stays itself); returns read()'s status.
template <typename Read>
int read_refusing_typed(const std::string& path, const char* format, Read&& read) {
  try {
    return read();
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    throw FormatError("'" + path + "' is not a readable " + format + " file (PCL's reader: " + e.what() + ")");
  }
}

}  // namespace occ_improve::detail
