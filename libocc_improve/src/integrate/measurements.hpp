#pragma once
// Insertion, step 1 and scheduling (private to src/integrate): points -> measurements (a point's
// position in the binning, its depth sigma and the columns its +-k sigma box overlaps), and the split of
// the tile rows into bands of equal work for the threads.
#include "occ_improve/integrate/integrate.hpp"
#include "support/default_init.hpp"

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace occ_improve::detail {

struct Measurement {
  double rho, azimuth, elevation;  ///< depth coordinate [m] and position in the binning's unit
  double sigma;  ///< depth sigma at rho: computed once, used in every tile the support spans
  int azimuth_first, azimuth_last, elevation_first, elevation_last;
};

// The measurements of one call in input order: each input chunk's valid points at the chunk's start, so
// the threads that convert the chunks write in place and nothing is merged.
struct MeasurementChunks {
  std::vector<Measurement, DefaultInitAllocator<Measurement>> slots;  ///< not zeroed: written before read
  std::vector<std::pair<std::size_t, std::size_t>> ranges;  ///< [begin, end) of each chunk's measurements
};

/// The points' measurements, in input order, converted in `threads` contiguous chunks in parallel; the
/// report counts received, inserted, invalid, out-of-field and beyond-range points.
InsertionReport to_measurements(PointSpan points, const GridGeometry& g, const SensorModel& model, int threads,
                                MeasurementChunks& measurements);

// The measurements of each tile row in input order (a measurement whose support spans two tile rows is
// in both), and each row's work in column updates: what the bands are balanced on and their tiles built
// from, so that a band reads its own rows' measurements rather than the whole frame's.
struct TileRows {
  std::vector<std::uint32_t> begin, items;  ///< row r's: items[begin[r]] .. items[begin[r + 1] - 1]
  std::vector<double> work;                 ///< row r's (measurement, column) pairs
  int count() const { return static_cast<int>(work.size()); }
};

/// The tile rows' measurements (a counting sort, on `threads` threads over the conversion's chunks).
TileRows bucket_by_tile_row(const MeasurementChunks& measurements, int tile_rows, int threads);

}  // namespace occ_improve::detail
