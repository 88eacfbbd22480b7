#include "integrate/measurements.hpp"

#include "occ_improve/cancel.hpp"
#include "support/parallel.hpp"

#include <algorithm>

namespace occ_improve::detail {

namespace {

// The region of support's half-widths, k sigma in the binning's unit: the same for every point of a call.
struct AngularSupport {
  double horizontal, vertical;
};

bool to_measurement(const float* p, const GridGeometry& g, const SensorModel& model, const AngularSupport& support,
                    Measurement& m, InsertionReport& report) {
  const double x = p[0], y = p[1], z = p[2];
  if (!is_valid_point(x, y, z)) {
    ++report.skipped_invalid;
    return false;
  }
  RayPosition r;
  if (!g.project(x, y, z, r)) {
    ++report.skipped_outside_fov;
    return false;
  }
  m.rho = r.depth;
  m.sigma = model.sigma_depth_at(r.depth);
  m.azimuth = r.horizontal;
  m.elevation = r.vertical;
  g.azimuth().overlapping(r.horizontal - support.horizontal, r.horizontal + support.horizontal, m.azimuth_first,
                          m.azimuth_last);
  g.elevation().overlapping(r.vertical - support.vertical, r.vertical + support.vertical, m.elevation_first,
                            m.elevation_last);
  if (r.depth >= g.depth().max()) ++report.beyond_depth_range;
  if (r.depth < g.depth().min()) ++report.nearer_than_depth_range;
  ++report.points_inserted;
  return true;
}

}  // namespace

InsertionReport to_measurements(PointSpan points, const GridGeometry& g, const SensorModel& model, int threads,
                                MeasurementChunks& measurements) {
  if (measurements.slots.size() < points.count) measurements.slots.resize(points.count);
  measurements.ranges.assign(static_cast<std::size_t>(threads), {0, 0});
  std::vector<InsertionReport> chunk_reports(static_cast<std::size_t>(threads));
  const AngularSupport support{model.support_horizontal(g.binning()), model.support_vertical(g.binning())};
  run_parts(threads, [&](int part, int parts) {
    const std::size_t begin = points.count * static_cast<std::size_t>(part) / static_cast<std::size_t>(parts);
    const std::size_t end = points.count * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(parts);
    std::size_t kept = begin;
    // Counted in a local report, copied once: the threads' reports share a cache line, and a count per
    // point written there cost two threads 12 ms for 307 200 points, against 9.6 ms counted locally.
    InsertionReport counts;
    for (std::size_t i = begin; i < end; ++i)
      if (poll_stop(i), to_measurement(points.xyz + i * points.stride_floats, g, model, support, measurements.slots[kept], counts))
        ++kept;
    chunk_reports[static_cast<std::size_t>(part)] = counts;
    measurements.ranges[static_cast<std::size_t>(part)] = {begin, kept};
  });
  InsertionReport report;
  report.points_received = points.count;
  for (const InsertionReport& r : chunk_reports) report += r;
  return report;
}

TileRows bucket_by_tile_row(const MeasurementChunks& measurements, int tile_rows, int threads) {
  constexpr int kTile = ColumnGrid::kTileSize;
  const auto rows = static_cast<std::size_t>(tile_rows), chunks = measurements.ranges.size();
  // Per chunk and row: how many measurements, then where the chunk's first one goes; and the work.
  std::vector<std::vector<std::uint32_t>> slot(chunks, std::vector<std::uint32_t>(rows, 0));
  std::vector<std::vector<double>> work(chunks, std::vector<double>(rows, 0.0));
  const auto for_each_row = [](const Measurement& m, auto&& visit) {
    for (int r = m.elevation_first / kTile; r <= m.elevation_last / kTile; ++r) {
      const int rows_in_tile = std::min(m.elevation_last, r * kTile + kTile - 1) - std::max(m.elevation_first, r * kTile) + 1;
      visit(static_cast<std::size_t>(r), rows_in_tile * (m.azimuth_last - m.azimuth_first + 1));
    }
  };
  const auto each_chunk = [&](auto&& body) {
    run_in_turn(threads, static_cast<int>(chunks), [&](int c, int) { body(static_cast<std::size_t>(c)); });
  };
  each_chunk([&](std::size_t c) {
    const auto [begin, end] = measurements.ranges[c];
    for (std::size_t i = begin; i < end; ++i)
      for_each_row((poll_stop(i), measurements.slots[i]), [&](std::size_t r, int pairs) {
        ++slot[c][r];
        work[c][r] += pairs;
      });
  });
  TileRows out;
  out.begin.assign(rows + 1, 0);
  out.work.assign(rows, 0.0);
  for (std::size_t r = 0; r < rows; ++r) {  // rows in order, chunks in input order within a row
    std::uint32_t next = out.begin[r];
    for (std::size_t c = 0; c < chunks; ++c) {
      const std::uint32_t n = slot[c][r];
      slot[c][r] = next;
      next += n;
      out.work[r] += work[c][r];
    }
    out.begin[r + 1] = next;
  }
  out.items.resize(out.begin[rows]);
  each_chunk([&](std::size_t c) {
    const auto [begin, end] = measurements.ranges[c];
    for (std::size_t i = begin; i < end; ++i)
      for_each_row((poll_stop(i), measurements.slots[i]), [&](std::size_t r, int) { out.items[slot[c][r]++] = static_cast<std::uint32_t>(i); });
  });
  return out;
}

}  // namespace occ_improve::detail
