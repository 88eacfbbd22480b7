// Inserts the built-in sample frame into a kinect_v1_paper grid and prints what happened.
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/sample_scene.hpp"
#include "occ_improve/maps/surface.hpp"

#include <cstdio>

int main() {
  using namespace occ_improve;
  const SensorPreset preset = kinect_v1_paper();
  ColumnGrid grid{GridGeometry(preset.geometry)};
  const SensorModel model(preset.model);
  const auto points = sample::generate_scene().points();
  const InsertionReport r = insert_points(grid, model, PointSpan::from(points));
  const SurfaceMap surface = compute_surface(grid);
  std::printf("points %zu: inserted %zu, invalid %zu, outside fov %zu, beyond range %zu\n", r.points_received,
              r.points_inserted, r.skipped_invalid, r.skipped_outside_fov, r.beyond_depth_range);
  std::printf("insertion %.1f ms, %zu column updates, store %.1f MB, %zu known surface columns\n", r.seconds * 1e3,
              r.column_updates, grid.memory_bytes() / 1e6, surface.known_count());
  return 0;
}
