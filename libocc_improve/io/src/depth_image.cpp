#include "occ_improve/io/depth_image.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/io/tiff.hpp"
#include "image_read.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace occ_improve {

void detail::require_image_size(const std::string& kind, const std::string& path, std::uint64_t width,
                                std::uint64_t height, std::uint64_t file_can_hold) {
  const std::uint64_t pixels = width * height;  // both < 2^32: no overflow
  std::string problem;
  if (pixels == 0) problem = "is empty";
  else if (pixels > kMaxDepthImagePixels) problem = "exceeds the cap of " + std::to_string(kMaxDepthImagePixels) + " pixels";
  else if (pixels > file_can_hold) problem = "is more than the file can hold (" + std::to_string(file_can_hold) + " pixels)";
  if (!problem.empty())
    throw FormatError(kind + " '" + path + "': width x height = " + std::to_string(width) + " x " +
                      std::to_string(height) + " " + problem);
}

namespace {

// The next token of a PGM header: white space and comments ('#' to the end of the line, which GIMP and
// ImageMagick write after the magic; a commented 16-bit PGM was refused as "not a 16-bit binary PGM") skipped.
std::string pgm_token(std::istream& in) {
  for (int c = in.peek(); c != std::char_traits<char>::eof(); c = in.peek()) {
    if (c == '#') {
      in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    } else if (std::isspace(c)) {
      in.get();
    } else {
      break;
    }
  }
  std::string token;
  in >> token;
  return token;
}

// A header number of at most 9 digits (no sign, nothing else), or -1.
int pgm_number(std::istream& in) {
  const std::string token = pgm_token(in);
  if (token.empty() || token.size() > 9 || token.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stoi(token);
}

DepthImage16 read_pgm16(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open depth image '" + path + "'");
  const std::string magic = pgm_token(in);
  const int width = pgm_number(in), height = pgm_number(in), max_value = pgm_number(in);
  if (magic != "P5" || !in || width <= 0 || height <= 0 || max_value < 256 || max_value > 65535)
    throw FormatError("'" + path + "' is not a 16-bit binary PGM (P5)");
  in.get();  // the single whitespace after the header
  const std::streamoff header = in.tellg();
  in.seekg(0, std::ios::end);
  const std::uint64_t pixel_bytes = static_cast<std::uint64_t>(in.tellg() - header);
  in.seekg(header);
  detail::require_image_size("depth image", path, static_cast<std::uint64_t>(width), static_cast<std::uint64_t>(height), pixel_bytes / 2);
  DepthImage16 image{width, height, {}};
  image.values.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  std::vector<unsigned char> raw(image.values.size() * 2);
  in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size()));
  if (static_cast<std::size_t>(in.gcount()) != raw.size()) throw FormatError("'" + path + "' is truncated");
  // The PGM standard says big-endian, but NYU's raw dumps are little-endian (with maximum 65535, so
  // every value "fits"). Take the order whose values fit the header's maximum, and of two that fit, the
  // one with the smaller largest value: depth data leaves its high byte mostly small.
  std::size_t big_ok = 0, little_ok = 0;
  int big_max = 0, little_max = 0;
  for (std::size_t i = 0; i < image.values.size(); ++i) {
    const int big = raw[2 * i] << 8 | raw[2 * i + 1], little = raw[2 * i + 1] << 8 | raw[2 * i];
    big_ok += big <= max_value ? 1 : 0;
    little_ok += little <= max_value ? 1 : 0;
    big_max = std::max(big_max, big);
    little_max = std::max(little_max, little);
  }
  const std::size_t n = image.values.size();
  const bool big_endian = big_ok == n && (little_ok != n || big_max <= little_max);
  for (std::size_t i = 0; i < image.values.size(); ++i)
    image.values[i] = big_endian ? static_cast<std::uint16_t>(raw[2 * i] << 8 | raw[2 * i + 1])
                                 : static_cast<std::uint16_t>(raw[2 * i + 1] << 8 | raw[2 * i]);
  return image;
}

// value x scale in double, rounded to float once: what the Python module's insert_depth(values, scale) and
// read_depth_png compute, so that one PNG read either way gives one map (float x float rounded twice: 1 ulp
// off on half of a frame's pixels).
float scaled(std::uint16_t v, double scale) { return static_cast<float>(v * scale); }

float decode(std::uint16_t v, DepthEncoding e) {
  switch (e) {
    case DepthEncoding::millimetres: return scaled(v, 1e-3);
    case DepthEncoding::tum_5000: return scaled(v, 1.0 / 5000.0);
    case DepthEncoding::sun_rotated_mm: return scaled(static_cast<std::uint16_t>((v >> 3) | (v << 13)), 1e-3);
    case DepthEncoding::kinect_disparity:
      if (v >= 1092) return 0.0f;  // 2047 = no return; beyond 1092.5 the model has no depth
      return 351.3f / (1092.5f - static_cast<float>(v));
  }
  return 0.0f;
}

}  // namespace

std::string lowercase_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos) return {};
  std::string e = path.substr(dot + 1);
  for (auto& ch : e) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return e;
}

DepthEncoding parse_depth_encoding(const std::string& name) {
  if (name == "mm") return DepthEncoding::millimetres;
  if (name == "tum") return DepthEncoding::tum_5000;
  if (name == "sun") return DepthEncoding::sun_rotated_mm;
  if (name == "nyu") return DepthEncoding::kinect_disparity;
  throw InvalidParameter("depth encoding '" + name + "' is invalid: must be one of mm, tum, sun, nyu");
}

const char* depth_encoding_name(DepthEncoding encoding) {
  switch (encoding) {
    case DepthEncoding::millimetres: return "mm";
    case DepthEncoding::tum_5000: return "tum";
    case DepthEncoding::sun_rotated_mm: return "sun";
    case DepthEncoding::kinect_disparity: return "nyu";
  }
  return "?";
}

DepthImage16 read_depth_image16(const std::string& path) {
  const std::string ext = lowercase_extension(path);
  if (ext == "png") return detail::read_grey_png(path, "depth image", false);
  if (ext == "pgm") return read_pgm16(path);
  if (ext == "tif" || ext == "tiff") return read_tiff_depth16(path);
  throw FormatError("'" + path + "': unsupported depth image type '." + ext + "' (expected .png, .pgm, .tif or .tiff)");
}

bool is_depth_image_path(const std::string& path) {
  const std::string ext = lowercase_extension(path);
  return ext == "png" || ext == "pgm" || ext == "tif" || ext == "tiff";
}

namespace {

// A Kinect's adjacent distinct depths lie 2.85e-3 z^2 m apart (z in m): 2.85e-6 v^2 units of v in millimetres.
constexpr double kKinectStepPerSquaredUnit = 2.85e-6;
// Below this median depth (metres) an encoding is not taken on the values' patterns alone: a Kinect
// measures from 0.5 m, and the presets' grids start there, so a reading whose typical depth lies nearer
// is what a millimetre image of round numbers looks like through the wrong scale.
constexpr double kNearestPlausibleMedianM = 0.5;
// SUN's shifted values read as millimetres lie 8 times too far: a true median of 0.5 m or more reads 4 m or
// more (metres).
constexpr double kSunShiftedMedianM = 8.0 * kNearestPlausibleMedianM;

// The nonzero values of an image as their occurrences (index = value), with the value at a given rank.
struct ValueCounts {
  std::vector<std::uint32_t> occurrences = std::vector<std::uint32_t>(std::size_t{1} << 16, 0);
  std::size_t nonzero = 0;

  std::size_t value_at_rank(std::size_t rank) const {  // rank < nonzero
    std::size_t value = 1, below = 0;
    while (below + occurrences[value] <= rank) below += occurrences[value++];
    return value;
  }
  /// The median step between the distinct values from the one at `rank` up (16 steps), over the step a
  /// Kinect's millimetres would take there; NaN with fewer than 8 steps.
  double step_ratio_at(std::size_t rank) const {
    const std::size_t from = value_at_rank(rank);
    std::vector<double> steps;
    for (std::size_t last = from, v = from + 1; v < occurrences.size() && steps.size() < 16; ++v)
      if (occurrences[v] > 0) {
        steps.push_back(static_cast<double>(v - last));
        last = v;
      }
    if (steps.size() < 8) return std::numeric_limits<double>::quiet_NaN();
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    const double v = static_cast<double>(from);
    return steps[steps.size() / 2] / (kKinectStepPerSquaredUnit * v * v);
  }
};

// TUM frames that are not multiples of 5 still carry a Kinect's quantisation, at 5 times fewer units per
// step than millimetres predict (a ratio of ~0.2; 0.14-0.23 on the data's SUN and TUM frames, 1.0-1.4 on
// millimetre ones). A Kinect's step grows as v^2, so the ratio is the same at every depth (within 15 %
// on those frames); a synthetic ramp's steps do not grow, and its ratio falls with depth. So: the ratio
// in (0.1, 0.45) at the quartiles and the median, and those three within a factor 1.5 of each other.
bool has_tum_quantisation(const ValueCounts& counts) {
  double lowest = std::numeric_limits<double>::infinity(), highest = 0.0;
  for (const std::size_t quarter : {1, 2, 3}) {
    const double ratio = counts.step_ratio_at(counts.nonzero * quarter / 4);
    if (!(ratio > 0.1 && ratio < 0.45)) return false;
    lowest = std::min(lowest, ratio);
    highest = std::max(highest, ratio);
  }
  return highest <= 1.5 * lowest;
}

}  // namespace

DepthEncoding guess_depth_encoding(const std::string& path, const DepthImage16& image) {
  std::size_t eleven_bit = 0, multiple_of_8 = 0, multiple_of_5 = 0, multiple_of_10 = 0;
  // How often each value occurs: medians and steps come from walks over it, where sorting a frame's
  // values took ~4 % of a depth sequence's run (occ_improve_map on 7-Scenes).
  ValueCounts counts;
  for (const std::uint16_t v : image.values) {
    eleven_bit += v <= 2047 ? 1 : 0;
    if (v == 0) continue;
    ++counts.nonzero;
    ++counts.occurrences[v];
    multiple_of_8 += v % 8 == 0 ? 1 : 0;
    multiple_of_5 += v % 5 == 0 ? 1 : 0;
    multiple_of_10 += v % 10 == 0 ? 1 : 0;
  }
  if (lowercase_extension(path) == "pgm" && eleven_bit == image.values.size()) return DepthEncoding::kinect_disparity;
  if (counts.nonzero < 100) return DepthEncoding::millimetres;
  const double n = static_cast<double>(counts.nonzero);
  const double median = static_cast<double>(counts.value_at_rank(counts.nonzero / 2));
  // SUN RGB-D: only depths beyond 8.192 m set the low 3 bits, a few percent of a frame at most; its
  // values read as millimetres lie 8 times too far, and only a fifth of them are multiples of 10 (those
  // of millimetres that are multiples of 5). A millimetre image of round depths (2000 everywhere, whole
  // centimetres) is multiples of 8 too, but of 10 as well.
  if (multiple_of_8 >= 0.9 * n && multiple_of_10 < 0.9 * n && median / 1000.0 >= kSunShiftedMedianM)
    return DepthEncoding::sun_rotated_mm;
  // TUM: the sensor's millimetres times 5, so about half of them odd multiples of 5 (a few interpolated
  // pixels break the pattern); millimetres rounded to centimetres are all multiples of 10.
  const bool tum_plausible = median / 5000.0 >= kNearestPlausibleMedianM;
  if (multiple_of_5 >= 0.99 * n && multiple_of_10 < 0.9 * n && tum_plausible) return DepthEncoding::tum_5000;
  // Other TUM frames are not multiples of 5: their depth quantisation tells (has_tum_quantisation). A
  // sensor without that quantisation (steps of ~1 unit) stays millimetres.
  if (tum_plausible && has_tum_quantisation(counts)) return DepthEncoding::tum_5000;
  return DepthEncoding::millimetres;
}

std::vector<float> depth_in_metres(const DepthImage16& image, DepthEncoding encoding) {
  std::vector<float> depth(image.values.size());
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = decode(image.values[i], encoding);
  return depth;
}

}  // namespace occ_improve
