#include "occ_improve/mapper.hpp"

#include "occ_improve/timing.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace occ_improve {
namespace {
// The cap is checked before the geometry allocates its depth axis (a huge depth_bins would allocate first).
const GeometryParams& within_cap(const GeometryParams& geometry, const GridOptions& options) {
  require_within_memory_cap(geometry, options.memory_cap_bytes);
  return geometry;
}

// The maps' buffers keep their addresses for the Mapper's life (Python's copy=False views read them in
// place): a recomputed map is copied into them, never moved over them (a move freed the buffers a view
// still read: a crash after clear_mask()). The shapes are the grid's, so the sizes match.
template <typename T>
void copy_into(std::vector<T>& kept, const std::vector<T>& fresh) {
  if (kept.size() != fresh.size())  // never: both are the grid's shape
    throw std::logic_error("Mapper: a recomputed map of " + std::to_string(fresh.size()) + " values for " +
                           std::to_string(kept.size()));
  std::copy(fresh.begin(), fresh.end(), kept.begin());
}
void copy_into(SurfaceMap& kept, const SurfaceMap& fresh) {
  copy_into(kept.depth_m, fresh.depth_m);
  copy_into(kept.probability, fresh.probability);
  copy_into(kept.bin, fresh.bin);
  copy_into(kept.unknown, fresh.unknown);
}
void copy_into(ImprovementMap& kept, const ImprovementMap& fresh) { copy_into(kept.value, fresh.value); }
}  // namespace

Mapper::Mapper(const SensorPreset& preset, const GridOptions& options)
    : Mapper(ColumnGrid(GridGeometry(within_cap(preset.geometry, options)), options),
             SensorModel(preset.model)) {}

Mapper::Mapper(ColumnGrid grid, const SensorModel& model) : grid_(std::move(grid)), model_(model) {
  model_.params().validate_for(grid_.geometry().params());  // sigmas the binning can mean (cost bound)
  grid_.take_changed_columns();  // the surface below already accounts for everything in the grid
  surface_ = compute_surface(grid_);
  improvement_ = compute_improvement(grid_.geometry(), model_, surface_);
}

// A call that throws part-way (a stop during the insertion: some bands stored, the incremental improvement
// not run, the changed columns lost; or a mask set before its improvement was computed) leaves the maps
// behind the grid. They are recomputed from it when next needed, as a loaded map's are.
template <class F>
auto Mapper::updating(F&& f) -> decltype(f()) {
  refresh_if_stale();
  try {
    return f();
  } catch (...) {
    stale_ = true;
    throw;
  }
}

void Mapper::refresh_if_stale() const {
  if (!stale_) return;
  SurfaceMap surface = compute_surface(grid_);
  ImprovementMap improvement = compute_improvement(grid_.geometry(), model_, surface);
  mask_improvement(column_mask_, improvement);
  copy_into(surface_, surface);
  copy_into(improvement_, improvement);
  pyramid_.reset();
  stale_ = false;
}

const SurfaceMap& Mapper::surface() const {
  refresh_if_stale();
  return surface_;
}

const ImprovementMap& Mapper::improvement() const {
  refresh_if_stale();
  return improvement_;
}

const ImprovementPyramid& Mapper::pyramid() const {
  refresh_if_stale();
  if (!pyramid_) pyramid_.emplace(improvement_, surface_);
  return *pyramid_;
}

MapperReport Mapper::insert(PointSpan points, const InsertionOptions& options, const PixelMask& mask) {
  set_mask(mask);
  return insert(points, options);
}

void Mapper::set_mask(const PixelMask& mask) { use_column_mask(mask_columns(grid_.geometry(), mask)); }

void Mapper::set_column_mask(const std::vector<std::uint8_t>& valid) {
  use_column_mask(column_mask_of(grid_.geometry(), valid));
}

void Mapper::use_column_mask(std::vector<std::uint8_t> columns) {
  updating([&] {
    const bool widened = !column_mask_.empty() && columns != column_mask_;
    column_mask_ = std::move(columns);
    // Columns the old mask hid may now be inside: their values come back only from a full computation.
    if (widened) copy_into(improvement_, compute_improvement(grid_.geometry(), model_, surface_));
    mask_improvement(column_mask_, improvement_);
    pyramid_.reset();  // every block may have changed: rebuilt when next asked
  });
}

void Mapper::clear_mask() {
  if (column_mask_.empty()) return;
  updating([&] {
    column_mask_.clear();
    copy_into(improvement_, compute_improvement(grid_.geometry(), model_, surface_));
    pyramid_.reset();
  });
}

MapperReport Mapper::insert(PointSpan points, const InsertionOptions& options) {
  return updating([&] { return insert_now(points, options); });
}

MapperReport Mapper::insert_now(PointSpan points, const InsertionOptions& options) {
  MapperReport report;
  std::vector<float> kept;  // the points inside the mask, when there is one
  if (!column_mask_.empty()) {
    report.points_masked = drop_masked_points(grid_.geometry(), column_mask_, points, kept);
    points = PointSpan{kept.data(), kept.size() / 3, 3};
  }
  // The surface is updated inside the insertion (its time is part of the insertion's).
  std::vector<ColumnIndex> changed;
  report.insertion = insert_points(grid_, model_, points, surface_, changed, options);
  report.insertion.points_received += report.points_masked;  // every point handed in is accounted for
  report.insertion.skipped_masked = report.points_masked;
  grid_.take_changed_columns();  // accounted for by `changed`
  report.surface_columns_changed = changed.size();
  const auto start = SteadyClock::now();
  // On the threads the caller gave the insertion: one means one for the whole frame.
  const std::vector<ColumnIndex> rays =
      update_improvement(grid_.geometry(), model_, surface_, changed, improvement_, options.threads);
  report.rays_recomputed = rays.size();
  mask_improvement(column_mask_, rays, improvement_);  // the recomputed rays outside the mask stay NaN
  if (pyramid_) {
    // A block depends on its rays' improvement and its columns' surface: both lists (duplicates are merged).
    changed.insert(changed.end(), rays.begin(), rays.end());
    pyramid_->update(improvement_, surface_, changed);
  }
  report.improvement_seconds = seconds_since(start);
  return report;
}

}  // namespace occ_improve
