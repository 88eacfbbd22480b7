// Insertion's entry points (eq. 2, integrate.hpp): points -> measurements (measurements.cpp), then the
// threads update bands of tile rows, one band at a time each (integrate.cpp).
#include "integrate/column_updates.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/maps/column_map.hpp"
#include "occ_improve/timing.hpp"
#include "support/parallel.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>

namespace occ_improve {

PointSpan PointSpan::from(const std::vector<Eigen::Vector3f>& points) {
  return {points.empty() ? nullptr : points.front().data(), points.size(), 3};
}

PointSpan PointSpan::from(const Eigen::Matrix3Xf& points) {
  return {points.data(), static_cast<std::size_t>(points.cols()), 3};
}

InsertionReport& InsertionReport::operator+=(const InsertionReport& o) {
  points_received += o.points_received;
  points_inserted += o.points_inserted;
  skipped_invalid += o.skipped_invalid;
  skipped_outside_fov += o.skipped_outside_fov;
  skipped_masked += o.skipped_masked;
  beyond_depth_range += o.beyond_depth_range;
  nearer_than_depth_range += o.nearer_than_depth_range;
  column_updates += o.column_updates;
  seconds += o.seconds;
  return *this;
}

void InsertionOptions::validate() const {
  const std::string range = "in [0, " + std::to_string(kMaxThreads) + "] (0: all cores)";
  detail::require_parameter(threads >= 0 && threads <= kMaxThreads, "threads", threads, range.c_str());
}

namespace {

void require_valid_span(PointSpan points) {
  if (points.count > 0 && points.xyz == nullptr) throw InvalidInput("insert_points: null point buffer with count > 0");
  if (points.stride_floats < 3) {
    std::ostringstream m;
    m << "insert_points: stride_floats = " << points.stride_floats << " is invalid: must be >= 3";
    throw InvalidInput(m.str());
  }
  if (points.count > std::numeric_limits<std::uint32_t>::max())  // tiles index measurements with 32 bits
    throw InvalidInput("insert_points: more than 2^32 - 1 points in one call; insert them in parts");
}

// Bands of tile rows per insertion thread (see insert).
constexpr int kBandsPerThread = 4;

// Buffers kept by the calling thread from one call to the next: a frame's measurements alone are
// megabytes, and fresh pages for them every frame cost more than the conversion itself.
struct InsertionWorkspace {
  detail::MeasurementChunks measurements;
  std::vector<std::vector<float>> scratch_rows;  ///< per worker, one depth row per column of a tile
};

// Both public insert_points: `surface` null, or the surface to keep current and where to list its changes.
//  1. Points -> measurements, in input order (parallel over contiguous chunks).
//  2. Measurements -> columns, tile by tile. Each band of tile rows is updated by one thread, so no two
//     threads share a tile or a column, and every column sees its measurements in input order: results do
//     not depend on threads.
InsertionReport insert(ColumnGrid& grid, const SensorModel& model, PointSpan points, const InsertionOptions& options,
                       SurfaceMap* surface, std::vector<ColumnIndex>* surface_changed) {
  const auto start = SteadyClock::now();
  options.validate();
  require_valid_span(points);
  const GridGeometry& g = grid.geometry();
  const int threads = detail::resolve_thread_count(options.threads);
  // References bound here: in the workers, `workspace` would name their own thread's.
  thread_local InsertionWorkspace workspace;
  detail::MeasurementChunks& measurements = workspace.measurements;
  std::vector<std::vector<float>>& scratch_rows = workspace.scratch_rows;
  InsertionReport report = detail::to_measurements(points, g, model, threads, measurements);

  const int tile_rows = (g.height() + ColumnGrid::kTileSize - 1) / ColumnGrid::kTileSize;
  const detail::TileRows rows = detail::bucket_by_tile_row(measurements, tile_rows, threads);
  // More bands than threads, taken in turn: the work estimate (pairs per tile row) misses how much a
  // pair costs, which varies with the scene by 10-30 % between halves of a frame.
  const int workers = std::max(1, std::min(threads, tile_rows));
  const int bands = workers == 1 ? 1 : std::min(tile_rows, kBandsPerThread * workers);
  // Bands of about equal estimated work (column updates); any split gives the same result: each column
  // has one owner.
  const std::vector<int> band_begin = detail::weighted_blocks(rows.work, bands);
  std::vector<std::size_t> updates(static_cast<std::size_t>(bands), 0);
  std::vector<std::vector<ColumnIndex>> changed(static_cast<std::size_t>(bands));
  if (scratch_rows.size() < static_cast<std::size_t>(workers)) scratch_rows.resize(static_cast<std::size_t>(workers));
  detail::run_in_turn(workers, bands, [&](int band, int worker) {
    const auto b = static_cast<std::size_t>(band);
    updates[b] = detail::update_band(grid, model, measurements, rows, band_begin[b], band_begin[b + 1],
                                     scratch_rows[static_cast<std::size_t>(worker)], surface, changed[b]);
  });
  for (std::size_t u : updates) report.column_updates += u;
  if (surface_changed) {
    surface_changed->clear();
    for (const auto& part : changed) surface_changed->insert(surface_changed->end(), part.begin(), part.end());
  }
  report.seconds = seconds_since(start);
  return report;
}

}  // namespace

InsertionReport insert_points(ColumnGrid& grid, const SensorModel& model, PointSpan points,
                              const InsertionOptions& options) {
  return insert(grid, model, points, options, nullptr, nullptr);
}

InsertionReport insert_points(ColumnGrid& grid, const SensorModel& model, PointSpan points, SurfaceMap& surface,
                              std::vector<ColumnIndex>& surface_changed, const InsertionOptions& options) {
  const GridGeometry& g = grid.geometry();
  require_shape("surface map", surface.shape(), "the grid", ColumnShape::of_grid(g.width(), g.height()));
  return insert(grid, model, points, options, &surface, &surface_changed);
}

InsertionReport insert_frames(ColumnGrid& grid, const SensorModel& model, const std::vector<PointSpan>& frames,
                              const InsertionOptions& options) {
  InsertionReport total;
  for (const PointSpan& f : frames) total += insert_points(grid, model, f, options);
  return total;
}

}  // namespace occ_improve
