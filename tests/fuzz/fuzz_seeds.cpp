// Writes small valid inputs of every fuzzed format into DIR/<target>/, with the project's own writers
// (and PCL's), as the starting points of `make fuzz`. Generated, so no data file is copied into the repo.
#include "occ_improve/io/map_io.hpp"
#include "occ_improve/mapper.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "support/tiff_writer.hpp"

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/io/png_io.h>
#include <pcl/point_types.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

void text(const fs::path& path, const std::string& content) { std::ofstream(path, std::ios::binary) << content; }

void pcd_seeds(const fs::path& dir) {
  pcl::PointCloud<pcl::PointXYZRGBL> cloud(4, 3);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].x = 0.1f * static_cast<float>(i % 4);
    cloud[i].y = 0.1f * static_cast<float>(i / 4);
    cloud[i].z = 1.5f;
    cloud[i].label = static_cast<std::uint32_t>(i % 3);
  }
  pcl::PCDWriter writer;
  writer.writeASCII((dir / "ascii.pcd").string(), cloud);
  writer.writeBinary((dir / "binary.pcd").string(), cloud);
  writer.writeBinaryCompressed((dir / "compressed.pcd").string(), cloud);
  pcl::PointCloud<pcl::PointXYZ> xyz(3, 1);
  writer.writeBinaryCompressed((dir / "xyz_compressed.pcd").string(), xyz);
}

void ply_seeds(const fs::path& dir) {
  pcl::PointCloud<pcl::PointXYZRGB> cloud(4, 3);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].x = 0.1f * static_cast<float>(i % 4);
    cloud[i].y = 0.1f * static_cast<float>(i / 4);
    cloud[i].z = 1.5f;
    cloud[i].r = static_cast<std::uint8_t>(20 * i);
  }
  pcl::io::savePLYFileBinary((dir / "organized_binary.ply").string(), cloud);
  pcl::io::savePLYFileASCII((dir / "organized_ascii.ply").string(), cloud);
  text(dir / "xyz_ascii.ply",
       "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 1\n0.5 0 2\n2 0 1\n");
}

// An 8 x 6 TIFF of `samples` x `bits` per pixel in strips of 2 rows.
void tiff(const fs::path& path, std::uint16_t bits, std::uint16_t samples, std::uint16_t compression) {
  const std::uint32_t width = 8, height = 6;
  std::vector<std::uint8_t> bytes(std::size_t{width} * height * samples * bits / 8);
  const std::size_t row_bytes = bytes.size() / height;
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(37 * (i / row_bytes + i % row_bytes));
  occ_improve::test::write_tiff(path.string(), width, height, bits, samples, bytes, 2, compression);
}

void tiff_seeds(const fs::path& dir) {
  tiff(dir / "depth16.tiff", 16, 1, COMPRESSION_NONE);
  tiff(dir / "depth16_lzw.tiff", 16, 1, COMPRESSION_LZW);
  tiff(dir / "depth16_deflate.tiff", 16, 1, COMPRESSION_ADOBE_DEFLATE);
  tiff(dir / "rgb8_packbits.tiff", 8, 3, COMPRESSION_PACKBITS);
}

void depth_seeds(const fs::path& png_dir, const fs::path& pgm_dir) {
  const int width = 8, height = 6;
  pcl::PointCloud<unsigned short> depth(width, height);
  for (std::size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<unsigned short>(1000 + 37 * i);
  pcl::io::savePNGFile((png_dir / "depth.png").string(), depth);
  std::string pgm = "P5 " + std::to_string(width) + " " + std::to_string(height) + " 65535\n";
  for (unsigned short v : depth) pgm += std::string{static_cast<char>(v >> 8), static_cast<char>(v & 0xff)};
  text(pgm_dir / "depth.pgm", pgm);
}

void map_seed(const fs::path& dir) {
  occ_improve::SensorPreset preset = occ_improve::kinect_v1_paper();
  preset.geometry.azimuth_bins = 8;
  preset.geometry.elevation_bins = 6;
  preset.geometry.depth_bins = 16;
  occ_improve::Mapper mapper(preset);
  const std::vector<Eigen::Vector3f> points = {{0.0f, 0.0f, 2.0f}, {0.1f, 0.05f, 3.0f}, {-0.2f, 0.1f, 1.0f}};
  mapper.insert(occ_improve::PointSpan::from(points));
  occ_improve::save_map((dir / "small.occmap").string(), mapper.grid(), mapper.model().params());
  // Version 5: a return record and the pose of the map's view after the columns.
  occ_improve::ReturnRecord returns = occ_improve::ReturnRecord::for_grid(8, 6);
  returns.record_shot({1, 7, 40}, {1, 0, 1});
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(0.5, -1.0, 2.0);
  occ_improve::save_map((dir / "posed.occmap").string(), mapper.grid(), mapper.model().params(), returns, pose);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DIR\n", argv[0]);
    return 1;
  }
  const fs::path root = argv[1];
  for (const char* t : {"pcd", "ply", "depth_png", "depth_pgm", "depth_tiff", "map", "intrinsics", "pose"})
    fs::create_directories(root / t);
  pcd_seeds(root / "pcd");
  ply_seeds(root / "ply");
  tiff_seeds(root / "depth_tiff");
  depth_seeds(root / "depth_png", root / "depth_pgm");
  map_seed(root / "map");
  text(root / "intrinsics" / "list.txt", "525 525 319.5 239.5 640 480\n");
  text(root / "intrinsics" / "matrix.txt", "585 0 320\n0 585 240\n0 0 1\n");
  text(root / "pose" / "frame.pose.txt",
       "9.9935108e-001 -2.3533077e-002 2.7267455e-002 -1.4496277e-001\n"
       "2.4040399e-002 9.9958366e-001 -1.8420193e-002 -9.5221795e-002\n"
       "-2.6821103e-002 1.9065253e-002 9.9945843e-001 1.2370843e-001\n"
       "0.0000000e+000 0.0000000e+000 0.0000000e+000 1.0000000e+000\n");
  std::printf("seeds written to %s\n", root.c_str());
  return 0;
}
