// PointImprovement is a custom point type: PCL's templates are instantiated for it here, as PCL asks for
// types it does not precompile.
#define PCL_NO_PRECOMPILE
#include "occ_improve/pcl/map_cloud.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/pcd_writer.hpp"

#include <limits>

namespace occ_improve {

pcl::PointCloud<PointImprovement> to_improvement_cloud(const GridGeometry& geometry, const SurfaceMap& surface,
                                                       const ImprovementMap& improvement) {
  const int width = geometry.width(), height = geometry.height();
  const std::size_t n = geometry.column_count();
  const ColumnShape grid = ColumnShape::of_grid(width, height);
  require_shape("to_improvement_cloud: surface map", surface.shape(), "the grid", grid);
  require_shape("to_improvement_cloud: improvement map", improvement.shape(), "the grid", grid);
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  pcl::PointCloud<PointImprovement> cloud;
  cloud.width = static_cast<std::uint32_t>(width);
  cloud.height = static_cast<std::uint32_t>(height);
  cloud.is_dense = false;
  cloud.points.resize(n);
  for (int e = 0; e < height; ++e) {
    for (int a = 0; a < width; ++a) {
      const ColumnIndex c = geometry.column(a, e);
      PointImprovement& p = cloud.points[c];
      p.surface_depth = surface.depth_m[c];
      p.probability = surface.probability[c];
      p.improvement = improvement.value[c];
      if (surface.unknown[c]) {
        p.x = p.y = p.z = nan;
      } else {
        const Eigen::Vector3d xyz = geometry.point(a, e, surface.depth_m[c]);
        p.x = static_cast<float>(xyz.x());
        p.y = static_cast<float>(xyz.y());
        p.z = static_cast<float>(xyz.z());
      }
      p.data[3] = 1.0f;
    }
  }
  return cloud;
}

void save_improvement_cloud(const std::string& path, const pcl::PointCloud<PointImprovement>& cloud) {
  save_pcd_binary(path, cloud);
}

}  // namespace occ_improve
