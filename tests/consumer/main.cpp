// A downstream program: uses the installed headers and libraries of every target.
#include <occ_improve/integrate.hpp>
#include <occ_improve/surface.hpp>

#include <cstdio>
#include <vector>

int main() {
  using namespace occ_improve;
  const SensorPreset preset = kinect_v1_paper();
  SphericalGrid grid{SphericalGeometry(preset.geometry)};
  std::vector<Eigen::Vector3f> points = {{0.0f, 0.0f, 2.0f}};
  const InsertionReport r = insert_points(grid, SensorModel(preset.model), PointSpan::from(points));
  const SurfaceMap s = compute_surface(grid);
  if (r.points_inserted != 1 || s.known_count() == 0) {
    std::fprintf(stderr, "consumer: unexpected result\n");
    return 1;
  }
  std::printf("consumer: occ_improve::core OK (%zu known columns)\n", s.known_count());
  return 0;
}
