#include "occ_improve/pcl/frame_io.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/pcl/pcd_header.hpp"
#include "occ_improve/pcl/ply_header.hpp"
#include "occ_improve/pcl/tiff_image.hpp"
#include "image_size.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <png.h>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
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

std::string extension_of(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos) return {};
  std::string e = path.substr(dot + 1);
  for (auto& ch : e) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return e;
}

// libpng reports errors through a callback that must not return: keep the message, jump back.
void png_error_to_string(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}
void png_ignore_warning(png_structp, png_const_charp) {}

// Frees libpng's read and info structs on every way out, exceptions included.
struct PngReader {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngReader() { png_destroy_read_struct(&png, &info, nullptr); }
};

// A grey PNG's values widened to 16 bits: 16-bit only for depth images, also 8-bit (and 1/2/4-bit,
// expanded) for masks. `what` names the file's role in messages ("depth image", "mask").
DepthImage16 read_grey_png(const std::string& path, const std::string& what, bool accept_8bit) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw IoError("cannot open " + what + " '" + path + "'");
  unsigned char signature[8];
  if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0)
    throw FormatError("'" + path + "' is not a PNG file");
  std::error_code ec;
  const std::uint64_t file_size = std::filesystem::file_size(path, ec);
  std::string png_message;
  PngReader reader;
  reader.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &png_message, &png_error_to_string, &png_ignore_warning);
  reader.info = reader.png ? png_create_info_struct(reader.png) : nullptr;
  if (!reader.png || !reader.info) throw IoError("libpng could not be initialised");
  png_structp png = reader.png;
  png_infop info = reader.info;
  DepthImage16 image;
  std::vector<std::uint8_t> narrow;  // 8-bit samples, widened after reading
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) throw FormatError("'" + path + "' is a corrupt or truncated PNG (" + png_message + ")");
  png_init_io(png, file.get());
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  const int bit_depth = png_get_bit_depth(png, info), colour = png_get_color_type(png, info);
  if ((bit_depth != 16 && !accept_8bit) || colour != PNG_COLOR_TYPE_GRAY) {
    std::ostringstream m;
    m << "'" << path << "' is a " << bit_depth << "-bit PNG of colour type " << colour << ": a " << what
      << " must be " << (accept_8bit ? "8-bit or 16-bit" : "16-bit") << " single-channel (grey)";
    throw FormatError(m.str());
  }
  // Deflate expands at most ~1032-fold: a file cannot hold more 2-byte pixels than that.
  detail::require_image_size(what, path, png_get_image_width(png, info), png_get_image_height(png, info),
                             ec ? kMaxDepthImagePixels : file_size * 1032 / 2);
  if (bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (bit_depth == 16) png_set_swap(png);  // PNG is big-endian; we read host-order uint16
  image.width = static_cast<int>(png_get_image_width(png, info));
  image.height = static_cast<int>(png_get_image_height(png, info));
  const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  image.values.resize(pixels);
  if (bit_depth < 16) narrow.resize(pixels);
  rows.resize(static_cast<std::size_t>(image.height));
  for (int v = 0; v < image.height; ++v) {
    const std::size_t offset = static_cast<std::size_t>(v) * static_cast<std::size_t>(image.width);
    rows[static_cast<std::size_t>(v)] =
        bit_depth == 16 ? reinterpret_cast<png_bytep>(image.values.data() + offset) : narrow.data() + offset;
  }
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  if (bit_depth < 16) std::copy(narrow.begin(), narrow.end(), image.values.begin());
  return image;
}

DepthImage16 read_png16(const std::string& path) { return read_grey_png(path, "depth image", false); }

}  // namespace

PixelMask read_mask_png(const std::string& path) {
  const DepthImage16 image = read_grey_png(path, "mask", true);
  PixelMask mask;
  mask.width = image.width;
  mask.height = image.height;
  mask.valid.resize(image.values.size());
  for (std::size_t i = 0; i < image.values.size(); ++i) mask.valid[i] = image.values[i] != 0;
  return mask;
}

namespace {

DepthImage16 read_pgm16(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open depth image '" + path + "'");
  std::string magic;
  int width = 0, height = 0, max_value = 0;
  in >> magic >> width >> height >> max_value;
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

float decode(std::uint16_t v, DepthEncoding e) {
  switch (e) {
    case DepthEncoding::millimetres: return v * 1e-3f;
    case DepthEncoding::tum_5000: return v / 5000.0f;
    case DepthEncoding::sun_rotated_mm: {
      const std::uint16_t mm = static_cast<std::uint16_t>((v >> 3) | (v << 13));
      return mm * 1e-3f;
    }
    case DepthEncoding::kinect_disparity:
      if (v >= 1092) return 0.0f;  // 2047 = no return; beyond 1092.5 the model has no depth
      return 351.3f / (1092.5f - static_cast<float>(v));
  }
  return 0.0f;
}

}  // namespace

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
  const std::string ext = extension_of(path);
  if (ext == "png") return read_png16(path);
  if (ext == "pgm") return read_pgm16(path);
  if (ext == "tif" || ext == "tiff") return read_tiff_depth16(path);
  throw FormatError("'" + path + "': unsupported depth image type '." + ext + "' (expected .png, .pgm, .tif or .tiff)");
}

bool is_depth_image_path(const std::string& path) {
  const std::string ext = extension_of(path);
  return ext == "png" || ext == "pgm" || ext == "tif" || ext == "tiff";
}

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// PCL's grabbers write `<stem>_depth.tiff` and the registered colour as `<stem>_rgb.tiff` beside it.
std::optional<Image> grabber_colour_beside(const std::string& depth_path, int width, int height) {
  for (const char* ext : {".tiff", ".tif"}) {
    const std::string depth_suffix = std::string("_depth") + ext;
    if (!ends_with(depth_path, depth_suffix)) continue;
    const std::string rgb = depth_path.substr(0, depth_path.size() - depth_suffix.size()) + "_rgb" + ext;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(rgb, ec)) return std::nullopt;
    Image colour = read_tiff_rgb8(rgb);
    if (colour.width != width || colour.height != height) return std::nullopt;  // not registered to this depth
    return colour;
  }
  return std::nullopt;
}

// The registered colour of an organized cloud's points (PCL packs rgb and rgba alike), row-major RGB.
Image colour_image(const pcl::PCLPointCloud2& blob) {
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  Image image;
  image.width = static_cast<int>(cloud.width);
  image.height = static_cast<int>(cloud.height);
  image.channels = 3;
  image.pixels.reserve(cloud.size() * 3);
  for (const auto& p : cloud) image.pixels.insert(image.pixels.end(), {p.r, p.g, p.b});
  return image;
}

// The file's sensor pose as LoadedFrame::viewpoint documents it.
std::optional<Eigen::Isometry3d> viewpoint_of(const Eigen::Vector4f& origin, const Eigen::Quaternionf& orientation,
                                              const std::string& path) {
  const Eigen::Quaterniond q = orientation.cast<double>();
  if (!origin.head<3>().allFinite() || !q.coeffs().allFinite() || std::abs(q.norm() - 1) > 1e-3)
    throw FormatError("'" + path + "': its viewpoint (sensor origin and orientation) is not a position and a unit quaternion");
  const Eigen::Quaterniond unit = q.normalized();
  constexpr double kExact = 1e-6;  // the files write these as plain 0s and 1s
  const bool at_origin = origin.head<3>().cast<double>().norm() < kExact;
  const bool identity = std::abs(std::abs(unit.w()) - 1) < kExact;
  const bool legacy_grabber = std::abs(std::abs(unit.x()) - 1) < kExact;  // qw 0, qx 1: see frame_io.hpp
  if (at_origin && (identity || legacy_grabber)) return std::nullopt;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = unit.toRotationMatrix();
  pose.translation() = origin.head<3>().cast<double>();
  return pose;
}

// A cloud PCL read (PCD or PLY) as a frame: x y z required as float, colour kept where it is organized.
LoadedFrame frame_of_blob(const pcl::PCLPointCloud2& blob, const std::string& path) {
  for (const char* axis : {"x", "y", "z"}) require_pcd_field(blob, path, axis, pcl::PCLPointField::FLOAT32);
  bool has_colour = false;
  for (const auto& f : blob.fields) has_colour |= f.name == "rgb" || f.name == "rgba";
  LoadedFrame frame;
  frame.path = path;
  // PCL's conversion takes &cloud[0] of the cloud it fills, undefined for one of no points (UBSan).
  if (std::uint64_t{blob.width} * blob.height == 0) return frame;
  pcl::fromPCLPointCloud2(blob, frame.cloud);
  if (has_colour && blob.height > 1) frame.colour = colour_image(blob);
  return frame;
}

}  // namespace

LoadedFrame load_pcd_frame(const std::string& path) {
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  read_pcd_file(path, blob, origin, orientation);
  LoadedFrame frame = frame_of_blob(blob, path);
  frame.viewpoint = viewpoint_of(origin, orientation, path);
  return frame;
}

LoadedFrame load_ply_frame(const std::string& path) {
  pcl::PCLPointCloud2 blob;
  read_ply_file(path, blob);
  return frame_of_blob(blob, path);
}

DepthEncoding guess_depth_encoding(const std::string& path, const DepthImage16& image) {
  std::size_t eleven_bit = 0, multiple_of_8 = 0, multiple_of_5 = 0;
  std::vector<std::uint16_t> nonzero;
  nonzero.reserve(image.values.size());
  for (const std::uint16_t v : image.values) {
    eleven_bit += v <= 2047 ? 1 : 0;
    if (v == 0) continue;
    nonzero.push_back(v);
    multiple_of_8 += v % 8 == 0 ? 1 : 0;
    multiple_of_5 += v % 5 == 0 ? 1 : 0;
  }
  if (extension_of(path) == "pgm" && eleven_bit == image.values.size()) return DepthEncoding::kinect_disparity;
  if (nonzero.size() < 100) return DepthEncoding::millimetres;
  const double n = static_cast<double>(nonzero.size());
  // SUN RGB-D: only depths beyond 8.192 m set the low 3 bits, a few percent of a frame at most.
  if (multiple_of_8 >= 0.9 * n) return DepthEncoding::sun_rotated_mm;
  // TUM: the sensor's millimetres times 5 (a few interpolated pixels break the pattern).
  if (multiple_of_5 >= 0.99 * n) return DepthEncoding::tum_5000;
  // Other TUM frames are not multiples of 5. Their depth quantisation tells: a Kinect's adjacent
  // distinct depths lie 2.85e-3 z^2 m apart (z in m), i.e. 2.85e-6 v^2 units in millimetres but 5 times
  // fewer units in TUM's scale. Compare the typical step between distinct values above the median with
  // the millimetre prediction; a sensor without that quantisation (steps of ~1 unit) stays millimetres.
  std::sort(nonzero.begin(), nonzero.end());
  const double median = nonzero[nonzero.size() / 2];
  std::vector<double> steps;
  for (std::size_t i = nonzero.size() / 2; i + 1 < nonzero.size() && steps.size() < 16; ++i)
    if (nonzero[i + 1] != nonzero[i]) steps.push_back(nonzero[i + 1] - nonzero[i]);
  if (steps.size() >= 8) {
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    const double ratio = steps[steps.size() / 2] / (2.85e-6 * median * median);
    if (ratio > 0.1 && ratio < 0.45) return DepthEncoding::tum_5000;
  }
  return DepthEncoding::millimetres;
}

LoadedFrame load_depth_frame(const std::string& path, const PinholeIntrinsics& k,
                             std::optional<DepthEncoding> encoding_or_guess) {
  const DepthImage16 raw = read_depth_image16(path);
  const DepthEncoding encoding = encoding_or_guess ? *encoding_or_guess : guess_depth_encoding(path, raw);
  if (raw.width != k.width || raw.height != k.height) {
    std::ostringstream m;
    m << "depth image '" << path << "' is " << raw.width << " x " << raw.height << " but the intrinsics say "
      << k.width << " x " << k.height;
    throw InvalidInput(m.str());
  }
  std::vector<float> depth(raw.values.size());
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = decode(raw.values[i], encoding);
  const auto points = depth_image_to_points(DepthImage{depth.data(), depth.size(), k});
  LoadedFrame frame;
  frame.path = path;
  frame.intrinsics = k;
  frame.encoding = encoding;
  frame.cloud = organized_cloud(points, k.width, k.height);
  frame.colour = grabber_colour_beside(path, k.width, k.height);
  return frame;
}

LoadedFrame load_frame(const std::string& path, const std::optional<PinholeIntrinsics>& intrinsics,
                       std::optional<DepthEncoding> encoding) {
  const std::string ext = extension_of(path);
  if (ext == "pcd") return load_pcd_frame(path);
  if (ext == "ply") return load_ply_frame(path);
  if (is_depth_image_path(path)) {
    if (!intrinsics) throw InvalidInput("depth image '" + path + "' needs camera intrinsics");
    return load_depth_frame(path, *intrinsics, encoding);
  }
  throw FormatError("'" + path + "': unsupported input type '." + ext + "' (expected .pcd, .ply, .png, .pgm, .tif or .tiff)");
}

Eigen::Isometry3d read_pose_matrix_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open pose file '" + path + "'");
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      if (!(in >> m(r, c))) throw FormatError("pose file '" + path + "' does not hold a 4x4 matrix");
  if (!(in >> std::ws).eof()) throw FormatError("pose file '" + path + "' holds more than a 4x4 matrix");
  if (!m.allFinite() || (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-6)
    throw FormatError("pose file '" + path + "' is not a rigid 4x4 transform (last row must be 0 0 0 1)");
  // Files carry 7-8 significant digits, so the rotation is only nearly orthonormal; Isometry3d's
  // inverse() transposes it, so project it onto the nearest rotation (SVD) to keep T^-1 T = I.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m.topLeftCorner<3, 3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
  if (rotation.determinant() < 0 || (rotation - m.topLeftCorner<3, 3>()).norm() > 1e-3)
    throw FormatError("pose file '" + path + "' does not hold a rotation (not orthonormal)");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;
  pose.translation() = m.topRightCorner<3, 1>();
  return pose;
}

std::string pose_file_for(const std::string& depth_path) {
  const std::string suffix = ".depth.png";
  if (!ends_with(depth_path, suffix)) return {};
  return depth_path.substr(0, depth_path.size() - suffix.size()) + ".pose.txt";
}

PinholeIntrinsics read_intrinsics_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open intrinsics file '" + path + "'");
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  if (!in.eof()) throw FormatError("intrinsics file '" + path + "' holds something that is not a number");
  PinholeIntrinsics k;
  if (v.size() == 9) {  // 3x3 matrix, row-major
    k.fx = v[0];
    k.cx = v[2];
    k.fy = v[4];
    k.cy = v[5];
  } else if (v.size() == 4 || v.size() == 6) {
    k.fx = v[0];
    k.fy = v[1];
    k.cx = v[2];
    k.cy = v[3];
    if (v.size() == 6) {
      // Checked before the cast: a double beyond int's range does not convert.
      for (const double size : {v[4], v[5]})
        if (!(size >= 1 && size <= 65536 && size == std::floor(size)))
          throw FormatError("intrinsics file '" + path + "': width and height must be whole numbers in [1, 65536]");
      k.width = static_cast<int>(v[4]);
      k.height = static_cast<int>(v[5]);
    }
  } else {
    throw FormatError("intrinsics file '" + path + "' must hold a 3x3 matrix or 'fx fy cx cy [width height]'");
  }
  try {
    k.validate();
  } catch (const InvalidParameter& e) {
    throw FormatError("intrinsics file '" + path + "': " + e.what());
  }
  return k;
}

bool is_depth_frame_name(const std::string& path) {
  const std::string name = std::filesystem::path(path).filename().string();
  for (const char* suffix : {".depth.png", "_depth.tiff", "_depth.tif"})
    if (name.size() > std::strlen(suffix) && ends_with(name, suffix)) return true;
  return false;
}

namespace {

// A frame with the intrinsics found for it and the pose file beside it.
FrameSource source_of(const std::string& path, const std::optional<PinholeIntrinsics>& intrinsics) {
  FrameSource source{path, intrinsics};
  const std::string pose_path = pose_file_for(path);
  std::error_code ec;
  if (!pose_path.empty() && std::filesystem::is_regular_file(pose_path, ec)) {
    source.pose = read_pose_matrix_file(pose_path);
    source.pose_source = std::filesystem::path(pose_path).filename().string();
  }
  return source;
}

std::optional<PinholeIntrinsics> intrinsics_beside(const std::filesystem::path& folder) {
  for (const auto& candidate : {folder / "camera-intrinsics.txt", folder.parent_path() / "camera-intrinsics.txt"}) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec)) return read_intrinsics_file(candidate.string());
  }
  return std::nullopt;
}

}  // namespace

std::vector<FrameSource> expand_input(const std::string& input) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(input);
  if (!fs::exists(p, ec))
    throw IoError("input '" + input + "' " +
                  (ec && ec != std::errc::no_such_file_or_directory ? "cannot be reached: " + ec.message() : "does not exist"));
  if (!fs::is_directory(p, ec)) {
    const fs::path folder = p.has_parent_path() ? p.parent_path() : fs::path(".");
    return {source_of(input, is_depth_image_path(input) ? intrinsics_beside(folder) : std::nullopt)};
  }
  std::vector<std::string> frames;
  for (fs::recursive_directory_iterator it(p, ec), end; it != end && !ec; it.increment(ec)) {
    if (it.depth() > 1) it.disable_recursion_pending();  // the folder and its seq-*/ subfolders
    if (it->is_regular_file(ec) && is_depth_frame_name(it->path().string())) frames.push_back(it->path().string());
  }
  if (ec) throw IoError("cannot list folder '" + input + "': " + ec.message());
  if (frames.empty()) throw InvalidInput("folder '" + input + "' holds no *.depth.png or *_depth.tif(f) frames");
  std::sort(frames.begin(), frames.end());
  const std::optional<PinholeIntrinsics> intrinsics = intrinsics_beside(p);
  std::vector<FrameSource> sources;
  for (const auto& f : frames) sources.push_back(source_of(f, intrinsics ? intrinsics : intrinsics_beside(fs::path(f).parent_path())));
  return sources;
}

}  // namespace occ_improve
