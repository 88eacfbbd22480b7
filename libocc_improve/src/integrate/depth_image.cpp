// Depth images -> points (pinhole back-projection) and their insertion.
#include "occ_improve/integrate/integrate.hpp"

#include "occ_improve/errors.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace occ_improve {

namespace {

// The image's own intrinsics first: NaN or 0 x 0 ones are reported as such, not as another camera.
void require_valid_intrinsics(const PinholeIntrinsics& k) {
  try {
    k.validate();
  } catch (const InvalidParameter& e) {
    throw InvalidInput(std::string("depth image intrinsics: ") + e.what());
  }
}

}  // namespace

std::vector<Eigen::Vector3f> depth_image_to_points(const DepthImage& image) {
  const PinholeIntrinsics& k = image.intrinsics;
  require_valid_intrinsics(k);
  const std::size_t expected = static_cast<std::size_t>(k.width) * static_cast<std::size_t>(k.height);
  if (image.pixel_count != expected) {
    std::ostringstream m;
    m << "depth image has " << image.pixel_count << " pixels but the intrinsics say " << k.width << " x " << k.height
      << " = " << expected;
    throw InvalidInput(m.str());
  }
  if (image.depth_m == nullptr) throw InvalidInput("depth image buffer is null");
  std::vector<Eigen::Vector3f> points(expected);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(k.width) + static_cast<std::size_t>(u);
      const float z = image.depth_m[i];
      if (!(z > 0.0f) || !std::isfinite(z)) {
        points[i] = Eigen::Vector3f(nan, nan, nan);
        continue;
      }
      points[i] = Eigen::Vector3f(static_cast<float>((u - k.cx) * z / k.fx), static_cast<float>((v - k.cy) * z / k.fy), z);
    }
  return points;
}

void require_grid_camera(const GridGeometry& geometry, const PinholeIntrinsics& intrinsics) {
  const std::optional<PinholeIntrinsics>& camera = geometry.params().camera;
  if (!camera || same_camera(*camera, intrinsics)) return;
  throw InvalidParameter("intrinsics (" + camera_text(intrinsics) + ") are not the camera the grid was built for (" +
                         camera_text(*camera) + "): its pixels would fall in other columns or outside the field " +
                         "of view; build the preset from these intrinsics");
}

InsertionReport insert_depth_image(ColumnGrid& grid, const SensorModel& model, const DepthImage& image,
                                   const InsertionOptions& options) {
  require_valid_intrinsics(image.intrinsics);
  require_grid_camera(grid.geometry(), image.intrinsics);
  const auto points = depth_image_to_points(image);
  return insert_points(grid, model, PointSpan::from(points), options);
}

}  // namespace occ_improve
