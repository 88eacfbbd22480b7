#pragma once
// The facade for "insert frames, ask where to look": a grid, its sensor model, the surface and the
// improvement map kept up to date together. No logic of its own: insert() is insert_points (keeping the
// surface current) + update_improvement + the multi-scale pyramid's update (multiscale.hpp), once
// pyramid() was asked.
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/grid/mask.hpp"
#include "occ_improve/integrate/integrate.hpp"
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/maps/multiscale.hpp"
#include "occ_improve/maps/surface.hpp"
#include "occ_improve/sensor/presets.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <cstddef>
#include <optional>

namespace occ_improve {

struct MapperReport {
  InsertionReport insertion;  ///< its seconds include the surface update, done column by column inside it
  double improvement_seconds = 0;  ///< the incremental improvement, and the pyramid's update once asked
  std::size_t surface_columns_changed = 0, rays_recomputed = 0;
  std::size_t points_masked = 0;  ///< valid points outside the mask, left out before the insertion (= insertion.skipped_masked)
};

class Mapper {
public:
  explicit Mapper(const SensorPreset& preset, const GridOptions& options = {});
  /// Takes over a grid (e.g. a loaded map) and computes its surface and improvement.
  Mapper(ColumnGrid grid, const SensorModel& model);

  /// Insertion with the surface kept current + incremental improvement.
  MapperReport insert(PointSpan points, const InsertionOptions& options = {});
  /// set_mask(mask), then insert(points, options).
  MapperReport insert(PointSpan points, const InsertionOptions& options, const PixelMask& mask);

  /// A validity / region-of-interest mask (mask.hpp) for the map from now on: later insertions leave out
  /// the points in pixels outside it (MapperReport::points_masked), and the improvement there is NaN (not
  /// observable: never ranked, in a region, planned or counted by the stop signal; grey in pictures).
  /// Replaces an earlier mask. Throws as mask_columns (no camera, another size).
  void set_mask(const PixelMask& mask);
  /// The same mask given per column (column_mask_of: one byte per column, row by row, nonzero = inside), for
  /// any grid, the grids without a camera too (the paper preset, lidar_rings). Throws as column_mask_of.
  void set_column_mask(const std::vector<std::uint8_t>& valid);
  /// Every column observable again (the improvement is recomputed).
  void clear_mask();
  /// One byte per column, 1 = inside the mask; empty without a mask.
  const std::vector<std::uint8_t>& column_mask() const { return column_mask_; }

  const GridGeometry& geometry() const { return grid_.geometry(); }
  const SensorModel& model() const { return model_; }
  const ColumnGrid& grid() const { return grid_; }
  /// The surface and improvement of the grid. After a call that threw part-way (Cancelled: a stop during an
  /// insertion; the grid keeps what was inserted before it), both are recomputed from the grid here or by
  /// the next insertion, so they never lag behind it.
  const SurfaceMap& surface() const;
  const ImprovementMap& improvement() const;
  /// The improvement on blocks of 2-16 columns and the depth samples' moments, kept with the map.
  /// The multi-scale improvement (multiscale.hpp). Built on the first call, then kept up to date by every
  /// insertion, so that a Mapper no coarse-to-fine planner or filter asks never pays for it (~16 ms of a
  /// 640 x 480 frame). Like the other accessors, not to be called while another thread inserts.
  const ImprovementPyramid& pyramid() const;

private:
  /// Runs a call that updates the grid and its maps; if it throws, the maps are marked stale.
  template <class F>
  auto updating(F&& f) -> decltype(f());
  /// Recomputes the surface, improvement and pyramid from the grid when a call threw part-way.
  void refresh_if_stale() const;
  MapperReport insert_now(PointSpan points, const InsertionOptions& options);
  /// Makes `columns` (0 / 1 bytes, one per column) the mask: the improvement masked, recomputed where it widened.
  void use_column_mask(std::vector<std::uint8_t> columns);

  ColumnGrid grid_;
  SensorModel model_;
  mutable SurfaceMap surface_;            // mutable: refreshed on access after an interrupted call
  mutable ImprovementMap improvement_;
  std::vector<std::uint8_t> column_mask_;  ///< empty: no mask
  mutable std::optional<ImprovementPyramid> pyramid_;  ///< empty until pyramid() is first asked
  mutable bool stale_ = false;  ///< a call threw part-way: surface_ and improvement_ may lag the grid
};

}  // namespace occ_improve
