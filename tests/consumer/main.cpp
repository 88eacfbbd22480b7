// A downstream program: uses the installed headers and libraries of every target it was given.
#include <occ_improve/integrate/integrate.hpp>
#include <occ_improve/maps/surface.hpp>
#ifdef HAVE_OCC_IO
#include <occ_improve/errors.hpp>
#include <occ_improve/io/depth_image.hpp>
#include <occ_improve/io/png.hpp>
#include <occ_improve/io/tiff.hpp>

#include <filesystem>
#endif
#ifdef HAVE_OCC_OCTOMAP
#include <occ_improve/octomap/export.hpp>
#endif
#ifdef HAVE_OCC_PCL
#include <occ_improve/pcl/conversion.hpp>
#include <occ_improve/pcl/frame_io.hpp>
#endif

#include <cstdint>
#include <cstdio>
#include <vector>

int main() {
  using namespace occ_improve;
  const SensorPreset preset = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(preset.geometry)};
  std::vector<Eigen::Vector3f> points;  // a 1 m x 1 m wall 2 m ahead
  for (float x = -0.5f; x <= 0.5f; x += 0.005f)
    for (float y = -0.5f; y <= 0.5f; y += 0.005f) points.emplace_back(x, y, 2.0f);
  const InsertionReport r = insert_points(grid, SensorModel(preset.model), PointSpan::from(points));
  const SurfaceMap s = compute_surface(grid);
  if (r.points_inserted != points.size() || s.known_count() == 0) {
    std::fprintf(stderr, "consumer: unexpected result from occ_improve::core\n");
    return 1;
  }
  std::printf("consumer: occ_improve::core OK (%zu known columns)\n", s.known_count());
#ifdef HAVE_OCC_IO
  const std::vector<std::uint8_t> png = encode_png(render_occupancy(s));
  if (png.size() < 8 || png[1] != 'P' || png[2] != 'N' || png[3] != 'G') {
    std::fprintf(stderr, "consumer: no PNG from occ_improve::io\n");
    return 1;
  }
  // The depth decoders: a 16-bit PNG read back through libpng, and libtiff linked (a missing TIFF is an IoError).
  const std::string depth_png = (std::filesystem::temp_directory_path() / "occ_improve_consumer_depth.png").string();
  write_png(depth_png, Image16{2, 1, {1500, 0}});
  const DepthImage16 depth = read_depth_image16(depth_png);
  std::filesystem::remove(depth_png);
  bool tiff_refused = false;
  try {
    read_tiff_depth16(depth_png + ".absent.tiff");
  } catch (const IoError&) {
    tiff_refused = true;
  }
  if (depth.width != 2 || depth.values.at(0) != 1500 || !tiff_refused) {
    std::fprintf(stderr, "consumer: the depth decoders of occ_improve::io failed\n");
    return 1;
  }
  std::printf("consumer: occ_improve::io OK (%zu-byte PNG, depth PNG read back, libtiff linked)\n", png.size());
#endif
#ifdef HAVE_OCC_OCTOMAP
  const auto tree = to_octree(grid, Eigen::Isometry3d::Identity(), 0.05);
  if (!tree || tree->size() == 0) {
    std::fprintf(stderr, "consumer: empty OcTree from occ_improve::octomap\n");
    return 1;
  }
  std::printf("consumer: occ_improve::octomap OK (%zu nodes)\n", tree->size());
#endif
#ifdef HAVE_OCC_PCL
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(0.0f, 0.0f, 2.0f));
  ColumnGrid from_pcl{GridGeometry(preset.geometry)};
  if (insert_points(from_pcl, SensorModel(preset.model), span_of(cloud)).points_inserted != 1 ||
      parse_depth_encoding("tum") != DepthEncoding::tum_5000) {
    std::fprintf(stderr, "consumer: unexpected result from occ_improve::pcl\n");
    return 1;
  }
  std::printf("consumer: occ_improve::pcl OK\n");
#endif
  return 0;
}
