#include "occ_improve/pcl/ply_header.hpp"

#include "header_text.hpp"
#include "occ_improve/errors.hpp"

#include <pcl/console/print.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <fstream>
#include <mutex>
#include <vector>

namespace occ_improve {
namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 16;
constexpr std::size_t kMaxProperties = 1024;

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw FormatError("PLY file '" + path + "': " + problem);
}

// Bytes of one value of a PLY type (both spellings PCL accepts), 0 for an unknown type.
std::uint64_t type_size(const std::string& type) {
  if (type == "char" || type == "int8" || type == "uchar" || type == "uint8") return 1;
  if (type == "short" || type == "int16" || type == "ushort" || type == "uint16") return 2;
  if (type == "int" || type == "int32" || type == "uint" || type == "uint32" || type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t min_binary_bytes = 0;  ///< per element: scalars, and each list's length field
  std::uint64_t pcl_point_bytes = 0;   ///< an upper bound of PCL's point step (it widens uchar colour to float)
  std::string colours{};               ///< the vertex's uchar colour properties in order, e.g. "red green blue"
  std::vector<std::string> property_names{};
};

// PCL 1.13 packs a vertex's uchar red, green, blue (and alpha) into one rgb(a) field that "red" opens
// and "blue" writes; a blue or alpha without the colours before it asserts (aborts) in
// PLYReader::vertexColorCallback (found by make fuzz). The "diffuse_" spellings count as the same.
const char* colour_channel(const std::string& type, const std::string& name) {
  if (type != "uchar" && type != "uint8") return nullptr;
  const std::string base = name.rfind("diffuse_", 0) == 0 ? name.substr(8) : name;
  for (const char* channel : {"red", "green", "blue", "alpha"})
    if (base == channel) return channel;
  return nullptr;
}
constexpr const char* kColourOrder = "red green blue alpha";

class HeaderParser {
public:
  explicit HeaderParser(const std::string& path) : path_(path) {}
  [[noreturn]] void fail(const std::string& problem) const { occ_improve::fail(path_, problem); }

  std::uint64_t number(const std::string& what, const std::string& text, std::uint64_t max) const {
    const bool digits = !text.empty() && text.size() <= 19 &&
                        std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
    const std::uint64_t v = digits ? std::stoull(text) : 0;
    if (!digits || v > max)
      fail(what + " '" + text + "' is invalid: must be a whole number in [0, " + std::to_string(max) + "]");
    return v;
  }

  void line(const std::vector<std::string>& t, PlyHeader& h) {
    const std::string& key = t[0];
    if (key == "comment") return;
    if (key == "format") {
      if (seen_format_ || t.size() != 3 || t[2] != "1.0") fail("needs one 'format <ascii|binary_*> 1.0' line");
      if (t[1] == "ascii") h.format = PlyHeader::Format::ascii;
      else if (t[1] == "binary_little_endian") h.format = PlyHeader::Format::binary_little_endian;
      else if (t[1] == "binary_big_endian") h.format = PlyHeader::Format::binary_big_endian;
      else fail("format '" + t[1] + "' is not ascii, binary_little_endian or binary_big_endian");
      seen_format_ = true;
    } else if (key == "obj_info") {
      obj_info(t, h);
    } else if (key == "element") {
      if (t.size() != 3) fail("'element' needs a name and a count");
      for (const Element& e : elements_)
        if (e.name == t[1]) fail("element '" + t[1] + "' is given twice");
      elements_.push_back(Element{t[1], number("count of element '" + t[1] + "'", t[2], UINT32_MAX)});
    } else if (key == "property") {
      property(t);
    } else {
      fail("unknown header line '" + key + "'");
    }
  }

  // After end_header: the data's least size against the file, PCL's buffer against the cap.
  void check_complete(PlyHeader& h, std::uint64_t available) const {
    if (!seen_format_) fail("no format line");
    std::uint64_t least_bytes = 0, grid = 0;
    for (const Element& e : elements_) {
      // ASCII: every value at least one character and a separator (the last one may end the file).
      const std::uint64_t per = h.format == PlyHeader::Format::ascii ? 2 * e.property_names.size() : e.min_binary_bytes;
      least_bytes += e.count * std::max<std::uint64_t>(per, 1);  // < 2^32 x 2^14: no overflow
      if (e.name == "vertex") h.vertices = e.count;
      if (!e.colours.empty() && e.colours != "red green blue" && e.colours != kColourOrder)
        fail("vertex colour properties must come as red, green, blue (then alpha), found '" + e.colours + "'");
      if (e.name == "range_grid") grid = e.count;
    }
    if (least_bytes > available + 1)
      fail("its elements need at least " + std::to_string(least_bytes) + " bytes, the file holds " +
           std::to_string(available) + " after the header");
    const std::uint64_t points = std::max(h.vertices, grid);
    const auto vertex = std::find_if(elements_.begin(), elements_.end(), [](const Element& e) { return e.name == "vertex"; });
    const std::uint64_t step = vertex == elements_.end() ? 0 : vertex->pcl_point_bytes;
    if (points * step > kMaxPcdDataBytes)
      throw ResourceLimit("PLY file '" + path_ + "': " + std::to_string(points) + " points x " + std::to_string(step) +
                          " bytes exceed the " + std::to_string(kMaxPcdDataBytes >> 20) + " MiB cap");
    if (h.columns || h.rows) {
      const std::uint64_t expected = grid ? grid : h.vertices;
      if (std::uint64_t{h.columns} * h.rows != expected)
        fail("obj_info num_cols x num_rows = " + std::to_string(h.columns) + " x " + std::to_string(h.rows) +
             " but it holds " + std::to_string(expected) + (grid ? " range_grid cells" : " vertices"));
    }
  }

  // ASCII data, from the first line after end_header (file line `line_number` + 1): PCL 1.13 reads values
  // leniently (detail::first_non_number), so every vertex line must hold one number per property. The
  // lines of elements before the vertices are skipped (one instance a line), those after are not read.
  void check_ascii_vertices(std::istream& in, std::uint64_t line_number) const {
    std::string line;
    std::vector<detail::Word> values;
    for (const Element& e : elements_) {
      for (std::uint64_t i = 0; i < e.count; ++i) {
        values.clear();
        while (values.empty()) {
          if (!std::getline(in, line))
            fail("ASCII data ends at element '" + e.name + "' " + std::to_string(i + 1) + " of " + std::to_string(e.count));
          ++line_number;
          detail::split_words(line, values);
        }
        if (e.name != "vertex") continue;
        const auto where = [&] { return "line " + std::to_string(line_number) + " (vertex " + std::to_string(i + 1) + ")"; };
        if (values.size() != e.property_names.size())
          fail(where() + " holds " + std::to_string(values.size()) + " values, the vertex has " +
               std::to_string(e.property_names.size()) + " properties");
        const std::size_t v = detail::first_non_number(values);
        if (v < values.size())
          fail(where() + ": '" + values[v].text() + "' for property '" + e.property_names[v] + "' is not a number");
      }
      if (e.name == "vertex") return;
    }
  }

private:
  // PCL takes num_cols / num_rows as the cloud's width / height; the vertex element only sets them when
  // one is still 0, so both must come together and before the elements, else width x height is neither.
  void obj_info(const std::vector<std::string>& t, PlyHeader& h) const {
    if (t.size() < 2 || (t[1] != "num_cols" && t[1] != "num_rows")) return;
    std::uint32_t& value = t[1] == "num_cols" ? h.columns : h.rows;
    if (value != 0) fail("obj_info " + t[1] + " is given twice");
    if (!elements_.empty()) fail("obj_info " + t[1] + " comes after an element");
    if (t.size() != 3) fail("obj_info " + t[1] + " needs one value");
    value = static_cast<std::uint32_t>(number("obj_info " + t[1], t[2], INT32_MAX));
    if (value == 0) fail("obj_info " + t[1] + " is 0");
  }

  void property(const std::vector<std::string>& t) {
    if (elements_.empty()) fail("a property comes before any element");
    Element& e = elements_.back();
    if (e.property_names.size() >= kMaxProperties) fail("element '" + e.name + "' has over " + std::to_string(kMaxProperties) + " properties");
    e.property_names.push_back(t.back());
    if (t.size() >= 2 && t[1] == "list") {
      if (t.size() != 5) fail("list property of element '" + e.name + "' needs 'list <count type> <type> <name>'");
      require_type(t[2], e);
      require_type(t[3], e);
      if (e.name == "vertex") fail("list property '" + t[4] + "' on vertices is not supported");
      e.min_binary_bytes += type_size(t[2]);
      return;
    }
    if (t.size() != 3) fail("property of element '" + e.name + "' needs '<type> <name>'");
    require_type(t[1], e);
    if (const char* channel = e.name == "vertex" ? colour_channel(t[1], t[2]) : nullptr) {
      e.colours += (e.colours.empty() ? "" : " ") + std::string(channel);
      if (std::string(kColourOrder).rfind(e.colours, 0) != 0)
        fail("vertex colour properties must come as red, green, blue (then alpha), found '" + e.colours + "'");
    }
    e.min_binary_bytes += type_size(t[1]);
    e.pcl_point_bytes += std::max<std::uint64_t>(type_size(t[1]), 4);
  }

  void require_type(const std::string& type, const Element& e) const {
    if (type_size(type) == 0) fail("property type '" + type + "' of element '" + e.name + "' is unknown");
  }

  const std::string& path_;
  bool seen_format_ = false;
  std::vector<Element> elements_;
};

// The header from the file's first 64 KiB only, so a file without line breaks costs no memory.
PlyHeader parse_header(std::istream& file, std::uint64_t file_size, const std::string& path) {
  std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kMaxHeaderBytes)), '\0');
  file.read(head.data(), static_cast<std::streamsize>(head.size()));
  HeaderParser parser(path);
  if (head.compare(0, 4, "ply\n") != 0 && head.compare(0, 5, "ply\r\n") != 0) parser.fail("not a PLY file (no 'ply' line first)");
  PlyHeader h;
  std::size_t at = head.find('\n') + 1;
  while (at < head.size()) {
    const std::size_t newline = head.find('\n', at);
    if (newline == std::string::npos) break;  // the header runs past the first 64 KiB or the file
    const std::string text = head.substr(at, newline - at);
    at = newline + 1;
    if (const char* refused = detail::refused_header_line(text, "not a PLY file (binary data before end_header)"))
      parser.fail(refused);
    const std::vector<std::string> t = detail::words(text);
    if (t.empty()) continue;
    if (t[0] == "end_header" && t.size() == 1) {
      h.data_offset = at;
      parser.check_complete(h, file_size - at);
      if (h.format == PlyHeader::Format::ascii) {
        file.clear();
        file.seekg(static_cast<std::streamoff>(at));
        parser.check_ascii_vertices(file, static_cast<std::uint64_t>(std::count(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(at), '\n')));
      }
      return h;
    }
    parser.line(t, h);
  }
  parser.fail("not a PLY file (no end_header line in the first 64 KiB)");
}

// What PCL built must be self-consistent before pcl::fromPCLPointCloud2 walks it (a camera element's
// viewport can reset width or height after the buffer was sized).
void require_consistent(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const std::uint64_t expected = std::uint64_t{blob.width} * blob.height * blob.point_step;
  if (expected != blob.data.size() || std::uint64_t{blob.row_step} != std::uint64_t{blob.point_step} * blob.width)
    fail(path, "width x height = " + std::to_string(blob.width) + " x " + std::to_string(blob.height) +
                   " does not match its " + std::to_string(blob.data.size()) + " bytes of points");
  for (const pcl::PCLPointField& f : blob.fields)
    if (std::uint64_t{f.offset} + static_cast<std::uint64_t>(pcl::getFieldSize(f.datatype)) * f.count > blob.point_step)
      fail(path, "property '" + f.name + "' lies outside the point");
}

// PCL's PLY reader warns about every camera property it does not use (focal, scalex, k1, ...): seven lines
// for each file PCL itself wrote. Its warnings are held back while it reads; errors still print. PLY
// reads are serialised so that nested guards restore the level in order.
class QuietPclWarnings {
public:
  QuietPclWarnings() : lock_(mutex()), before_(pcl::console::getVerbosityLevel()) {
    if (before_ > pcl::console::L_ERROR) pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
  }
  ~QuietPclWarnings() { pcl::console::setVerbosityLevel(before_); }
  QuietPclWarnings(const QuietPclWarnings&) = delete;
  QuietPclWarnings& operator=(const QuietPclWarnings&) = delete;

private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  pcl::console::VERBOSITY_LEVEL before_;
};

}  // namespace

PlyHeader validate_ply_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw IoError("cannot open PLY file '" + path + "'");
  const std::streamoff end = in.tellg();
  if (end < 0) throw IoError("cannot determine the size of PLY file '" + path + "' (not a regular file?)");
  if (end == 0) throw FormatError("PLY file '" + path + "' is empty");
  in.seekg(0);
  return parse_header(in, static_cast<std::uint64_t>(end), path);
}

void read_ply_file(const std::string& path, pcl::PCLPointCloud2& blob) {
  validate_ply_file(path);
  blob = detail::read_or_throw(path, "PLY", [path](detail::PclRead& out) {
           pcl::PLYReader reader;
           const QuietPclWarnings quiet;
           return reader.read(path, out.blob);
         }).blob;
  require_consistent(blob, path);
}

}  // namespace occ_improve
