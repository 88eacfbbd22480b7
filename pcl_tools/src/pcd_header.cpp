#include "occ_improve/pcl/pcd_header.hpp"

#include "header_text.hpp"
#include "occ_improve/errors.hpp"

#include <pcl/io/lzf.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cstring>
#include <fstream>

namespace occ_improve {
namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 16;
constexpr std::uint32_t kMaxFields = 1024, kMaxCount = 1 << 16;
// LZF encodes at most 264 bytes in a 3-byte back reference: a larger ratio cannot be real data.
constexpr std::uint64_t kMaxCompressionRatio = 128;

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw FormatError("PCD file '" + path + "': " + problem);
}

// The header's lines, one at a time, into a PcdHeader; every value checked as it is read.
class HeaderParser {
public:
  explicit HeaderParser(const std::string& path) : path_(path) {}

  [[noreturn]] void fail(const std::string& problem) const { occ_improve::fail(path_, problem); }

  std::uint64_t number(const std::string& key, const std::string& text, std::uint64_t min, std::uint64_t max) const {
    const bool digits = !text.empty() && text.size() <= 19 &&
                        std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
    const std::uint64_t v = digits ? std::stoull(text) : 0;
    if (!digits || v < min || v > max)
      fail(key + " " + text + " is invalid: must be a whole number in [" + std::to_string(min) + ", " +
           std::to_string(max) + "]");
    return v;
  }

  // One value per field, as many as FIELDS named.
  void per_field(const std::string& key, const std::vector<std::string>& values, PcdHeader& h) const {
    if (values.size() != h.fields.size())
      fail(key + " has " + std::to_string(values.size()) + " values for " + std::to_string(h.fields.size()) + " fields");
    for (std::size_t i = 0; i < values.size(); ++i) {
      PcdField& f = h.fields[i];
      const std::string what = key + " of field '" + f.name + "'";
      if (key == "SIZE") {
        f.size = static_cast<std::uint32_t>(number(what, values[i], 1, 8));
        if (f.size != 1 && f.size != 2 && f.size != 4 && f.size != 8) fail(what + " " + values[i] + " is not 1, 2, 4 or 8");
      } else if (key == "TYPE") {
        if (values[i] != "I" && values[i] != "U" && values[i] != "F") fail(what + " '" + values[i] + "' is not I, U or F");
        f.type = values[i][0];
      } else {
        f.count = static_cast<std::uint32_t>(number(what, values[i], 1, kMaxCount));
      }
    }
  }

  void line(const std::string& key, const std::vector<std::string>& values, PcdHeader& h) {
    if (std::find(seen_.begin(), seen_.end(), key) != seen_.end()) fail(key + " is given twice");
    seen_.push_back(key);
    auto single = [&]() -> const std::string& {
      if (values.size() != 1) fail(key + " must have one value, it has " + std::to_string(values.size()));
      return values[0];
    };
    if (key == "FIELDS") {
      if (values.empty() || values.size() > kMaxFields) fail("FIELDS must name 1 to " + std::to_string(kMaxFields) + " fields");
      for (const std::string& name : values) h.fields.push_back(PcdField{name});
    } else if (key == "SIZE" || key == "TYPE" || key == "COUNT") {
      if (h.fields.empty()) fail(key + " comes before FIELDS");
      per_field(key, values, h);
    } else if (key == "WIDTH") {
      h.width = static_cast<std::uint32_t>(number(key, single(), 0, UINT32_MAX));
    } else if (key == "HEIGHT") {
      h.height = static_cast<std::uint32_t>(number(key, single(), 0, UINT32_MAX));
    } else if (key == "POINTS") {
      h.points = number(key, single(), 0, UINT32_MAX);
    } else if (key == "DATA") {
      const std::string& d = single();
      if (d == "ascii") h.data = PcdHeader::Data::ascii;
      else if (d == "binary") h.data = PcdHeader::Data::binary;
      else if (d == "binary_compressed") h.data = PcdHeader::Data::binary_compressed;
      else fail("DATA '" + d + "' is not ascii, binary or binary_compressed");
    } else if (key != "VERSION" && key != "VIEWPOINT") {
      fail("unknown header line '" + key + "'");
    }
  }

  // After DATA: every required line present and the sizes agree with each other.
  void check_complete(const PcdHeader& h) const {
    for (const char* key : {"FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT", "POINTS"})
      if (std::find(seen_.begin(), seen_.end(), key) == seen_.end()) fail(std::string("no ") + key + " line");
    for (const PcdField& f : h.fields)
      if (f.type == 'F' && f.size != 4 && f.size != 8) fail("TYPE F of field '" + f.name + "' needs SIZE 4 or 8");
    // 64-bit product: WIDTH x HEIGHT wrapping to POINTS in 32 bits crashed PCL.
    const std::uint64_t product = std::uint64_t{h.width} * h.height;
    if (product != h.points)
      fail("WIDTH x HEIGHT = " + std::to_string(h.width) + " x " + std::to_string(h.height) + " = " +
           std::to_string(product) + " but POINTS " + std::to_string(h.points));
  }

private:
  const std::string& path_;
  std::vector<std::string> seen_;
};

// PCL 1.13's readHeader does not stop at DATA: it goes on reading lines as header while they start like
// one (by prefix, empty lines skipped), so a second header after DATA (say binary_compressed with an
// uncompressed size of 4 GiB) would replace the one checked here. Such a file is refused.
void require_no_header_after_data(const std::string& head, std::size_t at, const HeaderParser& parser) {
  static const char* const kPclKeys[] = {"VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT",
                                         "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
  while (at < head.size()) {
    const std::size_t end = std::min(head.find('\n', at), head.size());
    const std::string text = head.substr(at, end - at);
    at = end + 1;
    if (text.empty()) continue;  // PCL skips empty lines
    const std::vector<std::string> w = detail::words(text);
    const std::string first = w.empty() ? std::string() : w[0];
    if (first.rfind('#', 0) == 0) continue;  // and comments
    for (const char* key : kPclKeys)
      if (first.rfind(key, 0) == 0) parser.fail("a header line ('" + first + "') follows the DATA line");
    return;
  }
}

// The header is read from the file's first 64 KiB only, so a file without line breaks costs no memory.
PcdHeader parse_header(std::istream& file, std::uint64_t file_size, const std::string& path) {
  std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kMaxHeaderBytes)), '\0');
  file.read(head.data(), static_cast<std::streamsize>(head.size()));
  HeaderParser parser(path);
  PcdHeader h;
  std::size_t at = 0;
  while (at < head.size()) {
    const std::size_t newline = head.find('\n', at);
    if (newline == std::string::npos && head.size() < file_size) break;  // the line runs past the first 64 KiB
    const std::size_t next = newline == std::string::npos ? head.size() : newline + 1;
    const std::string text = head.substr(at, next - at);
    at = next;
    if (const char* refused = detail::refused_header_line(text, "not a PCD file (binary data before the DATA line)"))
      parser.fail(refused);
    std::vector<std::string> t = detail::words(text);
    // PCL 1.13's readHeader skips only truly empty lines: one of white space alone (" ", "\t", a CR of
    // CRLF) before DATA makes its read dereference null (found by make fuzz). Refused, not crashed on.
    if (t.empty() && text != "\n") parser.fail("a header line holds only white space (PCL cannot read such a file)");
    if (t.empty() || t[0][0] == '#') continue;
    const std::string key = t[0];
    t.erase(t.begin());
    parser.line(key, t, h);
    if (key == "DATA") {
      parser.check_complete(h);
      h.data_offset = at;
      require_no_header_after_data(head, at, parser);
      return h;
    }
  }
  parser.fail("not a PCD file (no header ending in a DATA line in the first 64 KiB)");
}

// binary_compressed: two 32-bit sizes, then LZF data that must expand to exactly the declared bytes.
void check_compressed(std::istream& in, std::uint64_t file_size, const PcdHeader& h, const std::string& path) {
  auto fail = [&](const std::string& problem) { occ_improve::fail(path, problem); };
  std::uint32_t sizes[2] = {0, 0};
  if (file_size - h.data_offset < sizeof sizes || !in.read(reinterpret_cast<char*>(sizes), sizeof sizes))
    fail("binary_compressed data has no size fields");
  const std::uint64_t compressed = sizes[0], uncompressed = sizes[1], expected = h.points * h.point_bytes();
  if (compressed > file_size - h.data_offset - sizeof sizes)
    fail("compressed size " + std::to_string(compressed) + " runs past the end of the file");
  if (uncompressed != expected)
    fail("uncompressed size " + std::to_string(uncompressed) + " is not POINTS x bytes per point = " +
                std::to_string(expected));
  if (expected == 0) return;
  if (uncompressed > kMaxCompressionRatio * compressed)
    fail("uncompressed size " + std::to_string(uncompressed) + " is over " +
                std::to_string(kMaxCompressionRatio) + " times the compressed size " + std::to_string(compressed));
  std::vector<char> packed(compressed), unpacked(uncompressed);
  if (!in.read(packed.data(), static_cast<std::streamsize>(compressed))) fail("compressed data is truncated");
  const unsigned got = pcl::lzfDecompress(packed.data(), static_cast<unsigned>(compressed), unpacked.data(),
                                          static_cast<unsigned>(uncompressed));
  if (got != uncompressed) fail("compressed data does not expand to the declared " + std::to_string(uncompressed) + " bytes");
}

// DATA ascii: PCL 1.13 reads values leniently (detail::first_non_number) and keeps a point whose line has
// too few or too many values as zeros after a warning that does not name the file, so a corrupt text
// cloud would be inserted as if it were valid. Every point's line (PCL skips empty lines and reads POINTS
// lines) must hold one number per value of the fields, and nothing but empty lines may follow the last.
void check_ascii_body(std::istream& in, const PcdHeader& h, const std::string& path) {
  std::vector<const PcdField*> field_of_value;
  for (const PcdField& f : h.fields) field_of_value.insert(field_of_value.end(), f.count, &f);
  std::uint64_t point = 0, line_number = 0;
  std::vector<detail::Word> values;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    if (line.empty()) continue;
    detail::split_words(line, values);
    const auto where = [&] { return "DATA ascii line " + std::to_string(line_number) + " (point " + std::to_string(point + 1) + ")"; };
    if (point == h.points) {
      if (values.empty()) continue;
      fail(path, where() + " is past the POINTS " + std::to_string(h.points) + " the header declares");
    }
    if (values.size() != field_of_value.size())
      fail(path, where() + " holds " + std::to_string(values.size()) + " values, the fields take " +
                     std::to_string(field_of_value.size()));
    const std::size_t v = detail::first_non_number(values);
    if (v < values.size())
      fail(path, where() + ": '" + values[v].text() + "' for field '" + field_of_value[v]->name + "' is not a number");
    ++point;
  }
  if (point < h.points)
    fail(path, "DATA ascii holds " + std::to_string(point) + " points, the header declares POINTS " + std::to_string(h.points));
}

}  // namespace

std::uint64_t PcdHeader::point_bytes() const {
  std::uint64_t bytes = 0;
  for (const PcdField& f : fields) bytes += std::uint64_t{f.size} * f.count;
  return bytes;
}

PcdHeader validate_pcd_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw IoError("cannot open PCD file '" + path + "'");
  const std::streamoff end = in.tellg();
  if (end < 0) throw IoError("cannot determine the size of PCD file '" + path + "' (not a regular file?)");
  const std::uint64_t file_size = static_cast<std::uint64_t>(end);
  if (file_size == 0) throw FormatError("PCD file '" + path + "' is empty");
  in.seekg(0);
  const PcdHeader h = parse_header(in, file_size, path);
  in.clear();
  in.seekg(static_cast<std::streamoff>(h.data_offset));

  const std::uint64_t data_bytes = h.points * h.point_bytes();  // < 2^32 x 2^30: no overflow
  if (data_bytes > kMaxPcdDataBytes)
    throw ResourceLimit("PCD file '" + path + "': POINTS " + std::to_string(h.points) + " x " +
                        std::to_string(h.point_bytes()) + " bytes per point exceed the " +
                        std::to_string(kMaxPcdDataBytes >> 20) + " MiB cap");
  const std::uint64_t available = file_size - std::min(file_size, h.data_offset);
  if (h.data == PcdHeader::Data::binary && data_bytes > available)
    fail(path, "DATA binary declares " + std::to_string(data_bytes) + " bytes, the file holds " + std::to_string(available));
  if (h.data == PcdHeader::Data::binary_compressed) check_compressed(in, file_size, h, path);
  if (h.data == PcdHeader::Data::ascii) {
    // Every value takes at least one character and one separator.
    std::uint64_t values = 0;
    for (const PcdField& f : h.fields) values += f.count;
    if (h.points * values > available / 2 + 1)
      fail(path, "DATA ascii declares " + std::to_string(h.points) + " points, more than the file's " +
                  std::to_string(available) + " bytes can hold");
    check_ascii_body(in, h, path);
  }
  return h;
}

namespace {

// pcl::PCLPointField's datatype as PCL's headers write it (TYPE and SIZE): "F 8" for FLOAT64.
std::string pcl_type_text(std::uint8_t datatype) {
  static const char* const kNames[] = {"?", "I 1", "U 1", "I 2", "U 2", "I 4", "U 4", "F 4", "F 8"};
  return datatype < sizeof(kNames) / sizeof(kNames[0]) ? kNames[datatype] : "type " + std::to_string(datatype);
}

}  // namespace

void require_pcd_field(const pcl::PCLPointCloud2& blob, const std::string& path, const std::string& name,
                       std::uint8_t datatype) {
  const auto f = std::find_if(blob.fields.begin(), blob.fields.end(),
                              [&](const pcl::PCLPointField& field) { return field.name == name; });
  // Not fail(): the blob may come from a PLY file as well.
  if (f == blob.fields.end()) throw FormatError("'" + path + "' has no '" + name + "' field");
  if (f->datatype != datatype || f->count != 1)
    throw FormatError("'" + path + "': field '" + name + "' is " + std::to_string(f->count) + " x " +
                      pcl_type_text(f->datatype) + " (TYPE SIZE), expected one " + pcl_type_text(datatype) +
                      (datatype == pcl::PCLPointField::FLOAT32 ? " (float32: convert the cloud's x y z)" : ""));
}

void read_pcd_file(const std::string& path, pcl::PCLPointCloud2& blob) {
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  read_pcd_file(path, blob, origin, orientation);
}

void read_pcd_file(const std::string& path, pcl::PCLPointCloud2& blob, Eigen::Vector4f& origin,
                   Eigen::Quaternionf& orientation) {
  validate_pcd_file(path);
  // The checks above refuse every input known to make PCL's reader throw; one they miss still ends as a
  // typed error naming the file.
  detail::PclRead read = detail::read_or_throw(path, "PCD", [path](detail::PclRead& out) {
    pcl::PCDReader reader;
    int version = 0;
    return reader.read(path, out.blob, out.origin, out.orientation, version);
  });
  blob = std::move(read.blob);
  origin = read.origin;
  orientation = read.orientation;
}

}  // namespace occ_improve
