#include "occ_improve/pcl/frame_io.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/camera_matrix.hpp"
#include "occ_improve/geometry/rotation.hpp"
#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/pcl/pcd_header.hpp"
#include "occ_improve/pcl/ply_header.hpp"
#include "occ_improve/io/tiff.hpp"
#include "header_text.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

namespace occ_improve {

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

// Whether x y z are one float64 each (Open3D writes PLY clouds so by default), which PCL's conversion
// leaves at 0: they are converted here. Otherwise they must be one float32 each (require_pcd_field).
bool xyz_in_doubles(const pcl::PCLPointCloud2& blob) {
  std::size_t doubles = 0;
  for (const auto& f : blob.fields)
    if ((f.name == "x" || f.name == "y" || f.name == "z") && f.datatype == pcl::PCLPointField::FLOAT64 && f.count == 1)
      ++doubles;
  return doubles == 3;
}

// The blob's float64 x y z as float, organized as the blob.
void read_double_xyz(const pcl::PCLPointCloud2& blob, pcl::PointCloud<pcl::PointXYZ>& cloud) {
  std::uint32_t offset[3] = {};
  for (const auto& f : blob.fields)
    for (int axis = 0; axis < 3; ++axis)
      if (f.name == std::string(1, static_cast<char>('x' + axis))) offset[axis] = f.offset;
  cloud.width = blob.width;
  cloud.height = blob.height;
  cloud.is_dense = false;
  cloud.resize(std::size_t{blob.width} * blob.height);
  for (std::uint32_t v = 0; v < blob.height; ++v)
    for (std::uint32_t u = 0; u < blob.width; ++u) {
      const std::uint8_t* point = blob.data.data() + std::size_t{v} * blob.row_step + std::size_t{u} * blob.point_step;
      double xyz[3];
      for (int axis = 0; axis < 3; ++axis) std::memcpy(&xyz[axis], point + offset[axis], sizeof(double));
      cloud[std::size_t{v} * blob.width + u] =
          pcl::PointXYZ(static_cast<float>(xyz[0]), static_cast<float>(xyz[1]), static_cast<float>(xyz[2]));
    }
}

// A cloud PCL read (PCD or PLY) as a frame: x y z as float (or double, converted), colour kept where it is
// organized.
LoadedFrame frame_of_blob(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const bool doubles = xyz_in_doubles(blob);
  if (!doubles)
    for (const char* axis : {"x", "y", "z"}) require_pcd_field(blob, path, axis, pcl::PCLPointField::FLOAT32);
  bool has_colour = false;
  for (const auto& f : blob.fields) has_colour |= f.name == "rgb" || f.name == "rgba";
  LoadedFrame frame;
  frame.path = path;
  // PCL's conversion takes &cloud[0] of the cloud it fills, undefined for one of no points (UBSan).
  if (std::uint64_t{blob.width} * blob.height == 0) return frame;
  if (doubles)
    read_double_xyz(blob, frame.cloud);
  else
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
  const std::vector<float> depth = depth_in_metres(raw, encoding);
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
  const std::string ext = lowercase_extension(path);
  if (ext == "pcd") return load_pcd_frame(path);
  if (ext == "ply") return load_ply_frame(path);
  if (is_depth_image_path(path)) {
    if (!intrinsics) throw InvalidInput("depth image '" + path + "' needs camera intrinsics");
    return load_depth_frame(path, *intrinsics, encoding);
  }
  throw FormatError("'" + path + "': unsupported input type '." + ext + "' (expected .pcd, .ply, .png, .pgm, .tif or .tiff)");
}

namespace {

// The white-space separated numbers of a small text file (a pose, intrinsics), each read whole: a word, "1.5x"
// or a NaN is named with its place (`place_of(i)` for the i-th value) instead of ending the list early and
// being reported as a short one.
std::vector<double> numbers_of_file(const std::string& path, const std::string& what,
                                    const std::function<std::string(std::size_t)>& place_of) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open " + what + " '" + path + "'");
  std::vector<double> values;
  std::string token;
  while (in >> token) {
    if (!detail::is_number(detail::Word{token.data(), token.data() + token.size()}))
      throw FormatError(what + " '" + path + "' holds '" + token + "' at " + place_of(values.size()) + ": not a number");
    values.push_back(std::strtod(token.c_str(), nullptr));
    if (!std::isfinite(values.back()))
      throw FormatError(what + " '" + path + "' holds a non-finite value at " + place_of(values.size() - 1) + " ('" +
                        token + "')");
  }
  return values;
}

}  // namespace

Eigen::Isometry3d read_pose_matrix_file(const std::string& path) {
  const std::vector<double> v = numbers_of_file(path, "pose file", [](std::size_t i) {
    return "row " + std::to_string(i / 4 + 1) + ", column " + std::to_string(i % 4 + 1);
  });
  if (v.size() != 16)
    throw FormatError("pose file '" + path + "' does not hold a 4x4 matrix (it holds " + std::to_string(v.size()) +
                      " values)");
  const Eigen::Matrix4d m = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(v.data());
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-6)
    throw FormatError("pose file '" + path + "' is not a rigid 4x4 transform (last row must be 0 0 0 1)");
  // Files carry 7-8 significant digits, so the rotation is only nearly orthonormal; Isometry3d's
  // inverse() transposes it, so it is projected onto the nearest rotation to keep T^-1 T = I.
  const std::optional<Eigen::Matrix3d> rotation = nearest_rotation(m.topLeftCorner<3, 3>());
  if (!rotation) throw FormatError("pose file '" + path + "' does not hold a rotation (not orthonormal)");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = *rotation;
  pose.translation() = m.topRightCorner<3, 1>();
  return pose;
}

std::string pose_file_for(const std::string& depth_path) {
  const std::string suffix = ".depth.png";
  if (!ends_with(depth_path, suffix)) return {};
  return depth_path.substr(0, depth_path.size() - suffix.size()) + ".pose.txt";
}

namespace {

// read_intrinsics_file; size_given tells whether the file held a width and height.
PinholeIntrinsics intrinsics_from_file(const std::string& path, bool& size_given) {
  throw_if_folder(path, "intrinsics file");
  const std::vector<double> v =
      numbers_of_file(path, "intrinsics file", [](std::size_t i) { return "position " + std::to_string(i + 1); });
  PinholeIntrinsics k;
  if (v.size() == 9) {  // K, row by row (a transposed K read as cx = cy = 0; a skew was taken silently)
    try {
      k = intrinsics_from_matrix({v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]}, k.width, k.height);
    } catch (const Error& e) {
      throw FormatError("intrinsics file '" + path + "': " + e.what());
    }
  } else if (v.size() == 4 || v.size() == 6) {
    k.fx = v[0];
    k.fy = v[1];
    k.cx = v[2];
    k.cy = v[3];
    size_given = v.size() == 6;
    if (size_given) {
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

}  // namespace

PinholeIntrinsics read_intrinsics_file(const std::string& path) {
  bool size_given = false;
  return intrinsics_from_file(path, size_given);
}

PinholeIntrinsics read_intrinsics_file(const std::string& path, const std::string& sized_by) {
  bool size_given = false;
  PinholeIntrinsics k = intrinsics_from_file(path, size_given);
  if (size_given) return k;
  DepthImage16 image;
  try {
    image = read_depth_image16(sized_by);
  } catch (const IoError&) {
    return k;  // the frame's own load names what is wrong with it; listing a folder does not
  } catch (const FormatError&) {
    return k;
  }
  // A camera whose principal point lies outside the image is another camera's (a dataset's file beside
  // an image of another size): refused as a size mismatch is, rather than sized by it.
  if (!(k.cx >= -0.5 && k.cx <= image.width - 0.5 && k.cy >= -0.5 && k.cy <= image.height - 0.5)) {
    std::ostringstream m;
    m << "depth image '" << sized_by << "' is " << image.width << " x " << image.height << " but the camera of '"
      << path << "' has its principal point at (" << k.cx << ", " << k.cy << "), outside it: not this image's camera";
    throw InvalidInput(m.str());
  }
  k.width = image.width;
  k.height = image.height;
  try {
    k.validate();
  } catch (const InvalidParameter& e) {
    throw FormatError("intrinsics file '" + path + "' sized as '" + sized_by + "': " + e.what());
  }
  return k;
}

bool is_depth_frame_name(const std::string& path) {
  const std::string name = std::filesystem::path(path).filename().string();
  for (const char* suffix : {".depth.png", "_depth.tiff", "_depth.tif"})
    if (name.size() > std::strlen(suffix) && ends_with(name, suffix)) return true;
  return false;
}

bool is_named_depth(const std::string& path) {
  return std::filesystem::path(path).filename().string().find("depth") != std::string::npos;
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

}  // namespace

std::optional<PinholeIntrinsics> intrinsics_beside(const std::filesystem::path& folder, const std::string& frame) {
  for (const auto& candidate : {folder / "camera-intrinsics.txt", folder.parent_path() / "camera-intrinsics.txt"}) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(candidate, ec)) continue;
    return read_intrinsics_file(candidate.string(), frame);
  }
  return std::nullopt;
}

std::vector<FrameSource> expand_input(const std::string& input) {
  namespace fs = std::filesystem;
  if (input.empty()) throw InvalidParameter("an input path is empty ('')");
  std::error_code ec;
  const fs::path p(input);
  if (!fs::exists(p, ec))
    throw IoError("input '" + input + "' " +
                  (ec && ec != std::errc::no_such_file_or_directory ? "cannot be reached: " + ec.message() : "does not exist"));
  if (!fs::is_directory(p, ec)) {
    const fs::path folder = p.has_parent_path() ? p.parent_path() : fs::path(".");
    return {source_of(input, is_depth_image_path(input) ? intrinsics_beside(folder, input) : std::nullopt)};
  }
  std::vector<std::string> frames;
  for (fs::recursive_directory_iterator it(p, ec), end; it != end && !ec; it.increment(ec)) {
    if (it.depth() > 1) it.disable_recursion_pending();  // the folder and its seq-*/ subfolders
    if (it->is_regular_file(ec) && is_depth_frame_name(it->path().string())) frames.push_back(it->path().string());
  }
  if (ec) throw IoError("cannot list folder '" + input + "': " + ec.message());
  if (frames.empty()) {
    // A TUM RGB-D folder lists its frames in depth.txt, under depth/: the one reader of that layout is the
    // live tool's (with the poses of groundtruth.txt).
    const bool tum = fs::exists(p / "depth.txt", ec);
    throw InvalidInput("folder '" + input + "' holds no *.depth.png or *_depth.tif(f) frames" +
                       (tum ? std::string(": a TUM RGB-D folder (depth.txt) is read by occ_improve_live -depth_dir, with "
                                          "its poses; give the other tools its depth/*.png files and -intrinsics")
                            : std::string()));
  }
  std::sort(frames.begin(), frames.end());
  const std::optional<PinholeIntrinsics> intrinsics = intrinsics_beside(p, frames.front());
  // Otherwise each subfolder's (seq-*/ beside their parent's file), found once per subfolder: sizing a
  // camera decodes a frame.
  std::map<fs::path, std::optional<PinholeIntrinsics>> by_folder;
  std::vector<FrameSource> sources;
  for (const auto& f : frames) {
    if (intrinsics) {
      sources.push_back(source_of(f, intrinsics));
      continue;
    }
    const fs::path folder = fs::path(f).parent_path();
    if (by_folder.count(folder) == 0) by_folder[folder] = intrinsics_beside(folder, f);
    sources.push_back(source_of(f, by_folder[folder]));
  }
  return sources;
}

FrameSource single_frame_source(const std::string& input, const std::string& flag) {
  std::vector<FrameSource> sources = expand_input(input);
  std::error_code ec;
  if (std::filesystem::is_directory(input, ec))
    throw InvalidParameter(flag + " takes one frame, and '" + input + "' is a folder of " +
                           std::to_string(sources.size()) + " frames: give one of them");
  return std::move(sources.front());
}

}  // namespace occ_improve
