#pragma once
// Reading range frames from files: PCD and PLY (organized or not, any XYZ point type) and depth images
// (16-bit PNG in millimetres or TUM's 1/5000 m, SUN3D's bit-rotated millimetres, NYU's raw Kinect
// disparity PGM, PCL grabbers' 16-bit TIFF in millimetres). Every failure throws occ_improve::IoError /
// FormatError / InvalidInput naming the file. The depth images are decoded by occ_improve::io
// (depth_image.hpp, no PCL); here they become clouds.
#include "occ_improve/io/depth_image.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/maps/image.hpp"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// A frame as a cloud in the sensor's optical frame; organized (width x height) where the source is.
struct LoadedFrame {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  std::string path;
  std::optional<PinholeIntrinsics> intrinsics;  ///< known for depth images
  std::optional<DepthEncoding> encoding;        ///< the encoding used, for depth images
  /// Registered RGB: of an organized PCD or PLY with rgb/rgba (PLY: red green blue), or of a
  /// `*_depth.tiff` from the `*_rgb.tiff` beside it when that has the same size (PCL grabbers' layout;
  /// a corrupt `*_rgb.tiff` is a FormatError naming it).
  std::optional<Image> colour;
  /// The sensor pose a PCD's VIEWPOINT records, camera-to-world (x_world = viewpoint * x_camera), never
  /// applied to `cloud`. Always nullopt for PLY and depth images: PCL 1.13's PLYReader parses a PLY's
  /// camera element but returns the default pose (its read() overwrites what the element gave). For a PCD,
  /// nullopt when it records
  ///  - the identity (`VIEWPOINT 0 0 0 1 0 0 0`, PCL's default), or
  ///  - `VIEWPOINT 0 0 0 0 1 0 0` (qw 0, qx 1: 180 degrees about x) at the origin, which old PCL grabbers
  ///    wrote while storing the points already in the optical frame (x right, y down, z forward), so
  ///    applying it would turn such clouds upside down (see shared/data/README.md).
  /// Otherwise the origin and the normalised orientation as an isometry. A non-finite origin or an
  /// orientation that is not a unit quaternion (|q| off 1 by more than 1e-3) is a FormatError.
  std::optional<Eigen::Isometry3d> viewpoint;
};

/// Any XYZ PCD. Throws IoError when unreadable, FormatError when it has no x/y/z fields.
LoadedFrame load_pcd_frame(const std::string& path);

/// Any PLY cloud PCL's PLYReader reads (ascii or binary; vertex x y z as float), organized width x height
/// where the file carries obj_info num_cols / num_rows (PCL's writer stores them). The header is checked
/// first (ply_header.hpp). Throws IoError when unreadable, FormatError when malformed or without x/y/z,
/// ResourceLimit when too large.
LoadedFrame load_ply_frame(const std::string& path);

/// A depth image back-projected through `intrinsics` (its size must match the image's, else InvalidInput).
/// Without an encoding, guess_depth_encoding() chooses it. A `*_depth.tif(f)` picks up its colour (above).
LoadedFrame load_depth_frame(const std::string& path, const PinholeIntrinsics& intrinsics,
                             std::optional<DepthEncoding> encoding = std::nullopt);

/// By extension (any case): .pcd -> PCD; .ply -> PLY; .png/.pgm/.tif/.tiff -> depth image (intrinsics
/// required, else InvalidInput).
LoadedFrame load_frame(const std::string& path, const std::optional<PinholeIntrinsics>& intrinsics,
                       std::optional<DepthEncoding> encoding = std::nullopt);

/// One frame named by a command-line input, with the intrinsics and pose found beside it (if any).
struct FrameSource {
  std::string path;
  std::optional<PinholeIntrinsics> intrinsics;  ///< from a camera-intrinsics.txt of the dataset layout
  /// Camera-to-world of the frame, from the 7-Scenes / 3DMatch `frame-NNNNNN.pose.txt` beside a
  /// `frame-NNNNNN.depth.png` (pose_file_for); nullopt without one. Not applied by expand_input.
  std::optional<Eigen::Isometry3d> pose{};
  std::string pose_source{};  ///< the pose file's name, e.g. "frame-000150.pose.txt"; "" without a pose
};

/// A command-line input as frames. A file is itself; a depth image also picks up a camera-intrinsics.txt
/// beside it or one folder up (the 3DMatch / SUN3D / 7-Scenes layout), and its pose file
/// (FrameSource::pose). A folder is its *.depth.png frames and its *_depth.tif(f) frames (PCL ImageGrabber
/// layout; seq-*/ subfolders included), sorted by path, with its camera-intrinsics.txt (the TIFF layout
/// has none: its calibration is in the PCLZF folder's XML, so those frames need intrinsics from the user).
/// Throws IoError when the input does not exist, InvalidInput for a folder with no depth frames,
/// FormatError for a malformed pose file.
std::vector<FrameSource> expand_input(const std::string& input);
/// Whether a stop request abandoned a PCL read (PCD/PLY readers poll none: theirs runs on a thread of its
/// own, detached when the caller stops waiting). A program that sees it ends with std::_Exit once its own
/// cleanup is done, so that no static object is destroyed under the running read.
bool pcl_read_abandoned();
/// The one frame a file input is (expand_input's rules: the intrinsics and pose beside it); a folder is
/// InvalidParameter naming `flag` and how many frames it holds (a tool that takes one frame).
FrameSource single_frame_source(const std::string& input, const std::string& flag);

/// Whether the file name is a dataset folder's depth frame: 7-Scenes / 3DMatch `*.depth.png`, PCL
/// ImageGrabber `*_depth.tif(f)` (what expand_input takes from a folder; its other images are colour).
bool is_depth_frame_name(const std::string& path);
/// Whether the file name holds "depth" (Open3D's samples `TUM_depth.png` beside `TUM_color.png`, NYU's
/// `*_depth.pgm`): in a folder where some images do, the others are colour frames, not depth.
bool is_named_depth(const std::string& path);

/// The pose file of a 7-Scenes / 3DMatch depth frame: `<dir>/frame-NNNNNN.depth.png` ->
/// `<dir>/frame-NNNNNN.pose.txt` (whether it exists or not); "" for a name not of that layout.
std::string pose_file_for(const std::string& depth_path);

/// Reads a 4x4 camera-to-world matrix (7-Scenes .pose.txt); the rotation is projected onto the nearest
/// rotation matrix. Throws IoError, FormatError (not 4x4, last row not 0 0 0 1, not a rotation).
Eigen::Isometry3d read_pose_matrix_file(const std::string& path);

/// Intrinsics from a text file: either "fx fy cx cy [width height]" or a 3x3 matrix (7-Scenes/3DMatch
/// camera-intrinsics.txt); width/height default to 640 x 480.
PinholeIntrinsics read_intrinsics_file(const std::string& path);
/// The same, with the width and height of the depth image `sized_by` where the file gives none (a 3x3
/// matrix or four numbers): the camera of a dataset folder is the size of its frames. An image that does
/// not read leaves 640 x 480 (its own load reports it).
PinholeIntrinsics read_intrinsics_file(const std::string& path, const std::string& sized_by);

/// The camera-intrinsics.txt of `folder` or of its parent (7-Scenes, 3DMatch), if any. Where it gives no
/// size (a 3 x 3 matrix), the depth image `frame` sizes it: the file says nothing of the size, so no image
/// is refused for one (640 x 480 was assumed for images not named as a dataset's frames).
std::optional<PinholeIntrinsics> intrinsics_beside(const std::filesystem::path& folder, const std::string& frame);

}  // namespace occ_improve
