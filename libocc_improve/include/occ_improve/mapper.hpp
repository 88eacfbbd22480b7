#pragma once
// The facade for "insert frames, ask where to look": a grid, its sensor model, the surface and the
// improvement map kept up to date together. No logic of its own: insert() is insert_points (keeping the
// surface current) + update_improvement + the multi-scale pyramid's update (multiscale.hpp).
#include "occ_improve/grid.hpp"
#include "occ_improve/improvement.hpp"
#include "occ_improve/integrate.hpp"
#include "occ_improve/multiscale.hpp"
#include "occ_improve/presets.hpp"
#include "occ_improve/sensor_model.hpp"
#include "occ_improve/surface.hpp"

#include <cstddef>

namespace occ_improve {

struct MapperReport {
  InsertionReport insertion;  ///< its seconds include the surface update, done column by column inside it
  double improvement_seconds = 0;  ///< the incremental improvement and the pyramid's update
  std::size_t surface_columns_changed = 0, rays_recomputed = 0;
};

class Mapper {
public:
  explicit Mapper(const SensorPreset& preset, const GridOptions& options = {});
  /// Takes over a grid (e.g. a loaded map) and computes its surface and improvement.
  Mapper(SphericalGrid grid, const SensorModel& model);

  /// Insertion with the surface kept current + incremental improvement.
  MapperReport insert(PointSpan points, const InsertionOptions& options = {});

  const SphericalGeometry& geometry() const { return grid_.geometry(); }
  const SensorModel& model() const { return model_; }
  const SphericalGrid& grid() const { return grid_; }
  const SurfaceMap& surface() const { return surface_; }
  const ImprovementMap& improvement() const { return improvement_; }
  /// The improvement on blocks of 2-16 columns and the depth samples' moments, kept with the map.
  const ImprovementPyramid& pyramid() const { return pyramid_; }

private:
  SphericalGrid grid_;
  SensorModel model_;
  SurfaceMap surface_;
  ImprovementMap improvement_;
  ImprovementPyramid pyramid_;
};

}  // namespace occ_improve
