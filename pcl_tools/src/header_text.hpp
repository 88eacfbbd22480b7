#pragma once
// Private to pcl_tools/src: the text of PCD and PLY files before PCL reads them (header lines, ASCII values).
#include "occ_improve/errors.hpp"

#include <Eigen/Geometry>
#include <pcl/PCLPointCloud2.h>

#include <charconv>
#include <cstdlib>
#include <exception>
#include <functional>
#include <new>
#include <string>
#include <system_error>
#include <vector>

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

/// A word of a line: [begin, end).
struct Word {
  const char* begin;
  const char* end;
  std::string text() const { return std::string(begin, end); }
};

/// The words of `line` (split at white space: space, \t \n \v \f \r), into `out` (reused between lines:
/// the data checks read millions of values).
inline void split_words(const std::string& line, std::vector<Word>& out) {
  out.clear();
  const char* c = line.data();
  const char* const end = c + line.size();
  const auto space = [](char ch) { return ch == ' ' || (ch >= '\t' && ch <= '\r'); };
  while (c != end) {
    while (c != end && space(*c)) ++c;
    const char* const start = c;
    while (c != end && !space(*c)) ++c;
    if (c != start) out.push_back({start, c});
  }
}

/// A line's words as strings (the header checks').
inline std::vector<std::string> words(const std::string& line) {
  std::vector<Word> split;
  split_words(line, split);
  std::vector<std::string> t;
  for (const Word& w : split) t.push_back(w.text());
  return t;
}

/// Whether a word is wholly a number as strtod reads it (digits, exponents, nan, inf; a value beyond
/// double's range is still a number). std::from_chars reads a subset of that syntax, quickly; a word it
/// refuses (a leading '+', a hex float) is left to strtod.
inline bool is_number(const Word& w) {
  double value = 0;
  const std::from_chars_result r = std::from_chars(w.begin, w.end, value);
  if (r.ptr == w.end && w.begin != w.end && (r.ec == std::errc() || r.ec == std::errc::result_out_of_range)) return true;
  const std::string text = w.text();
  char* parsed = nullptr;
  std::strtod(text.c_str(), &parsed);
  return !text.empty() && parsed == text.c_str() + text.size();
}

/// The first of `values` that is not wholly a number, or values.size(). PCL 1.13's ASCII readers read
/// "1.5abc" as 1.5 and "foo" as 0 (PCD) or NaN (PLY), so a corrupt text cloud would be read as valid points
/// or as invalid ones for the wrong reason.
inline std::size_t first_non_number(const std::vector<Word>& values) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!is_number(values[i])) return i;
  return values.size();
}

/// What a PCL reader gives: the blob, and a PCD's VIEWPOINT.
struct PclRead {
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
};

/// PCL's read on a file the header checks passed: `read` fills a PclRead of its own and returns PCL's
/// status. A failed status, or an exception it throws (out of memory stays itself), becomes a FormatError
/// naming the file. PCL's readers poll no stop request, and an ASCII PLY of a few million points reads for
/// seconds: `read` runs on a thread of its own while the caller polls every 50 ms, and a stop request
/// abandons it (Cancelled; its thread runs on, detached, into state it owns: pcl_read_abandoned()). So
/// `read` must capture nothing by reference.
PclRead read_or_throw(const std::string& path, const char* format, std::function<int(PclRead&)> read);

}  // namespace occ_improve::detail
