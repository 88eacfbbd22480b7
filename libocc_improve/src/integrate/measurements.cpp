#include "integrate/measurements.hpp"

#include "occ_improve/cancel.hpp"
#include "support/parallel.hpp"

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
    for (std::size_t i = begin; i < end; ++i)
      if (poll_stop(i), to_measurement(points.xyz + i * points.stride_floats, g, model, support, measurements.slots[kept],
                         chunk_reports[static_cast<std::size_t>(part)]))
        ++kept;
    measurements.ranges[static_cast<std::size_t>(part)] = {begin, kept};
  });
  InsertionReport report;
  report.points_received = points.count;
  for (const InsertionReport& r : chunk_reports) report += r;
  return report;
}

std::vector<int> balanced_bands(const MeasurementChunks& measurements, int tile_rows, int parts) {
  std::vector<double> work(static_cast<std::size_t>(tile_rows), 0.0);
  measurements.for_each([&](std::size_t, const Measurement& m) {
    const double columns = m.azimuth_last - m.azimuth_first + 1;
    for (int e = m.elevation_first; e <= m.elevation_last; ++e)
      work[static_cast<std::size_t>(e / ColumnGrid::kTileSize)] += columns;
  });
  double total = 0;
  for (double w : work) total += w;
  std::vector<int> begin(static_cast<std::size_t>(parts) + 1, tile_rows);
  begin[0] = 0;
  double sum = 0;
  int part = 1;
  for (int r = 0; r < tile_rows && part < parts; ++r) {
    sum += work[static_cast<std::size_t>(r)];
    if (sum >= total * part / parts) begin[static_cast<std::size_t>(part++)] = r + 1;
  }
  return begin;
}

}  // namespace occ_improve::detail
