#pragma once
// Insertion, step 1 and scheduling (private to src/integrate): points -> measurements (a point's
// position in the binning, its depth sigma and the columns its +-k sigma box overlaps), and the split of
// the tile rows into bands of equal work for the threads.
#include "occ_improve/integrate/integrate.hpp"

#include <cstddef>
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
  std::vector<Measurement> slots;
  std::vector<std::pair<std::size_t, std::size_t>> ranges;  ///< [begin, end) of each chunk's measurements

  template <typename Visit>
  void for_each(Visit&& visit) const {
    for (const auto& [begin, end] : ranges)
      for (std::size_t i = begin; i < end; ++i) visit(i, slots[i]);
  }
};

/// The points' measurements, in input order, converted in `threads` contiguous chunks in parallel; the
/// report counts received, inserted, invalid, out-of-field and beyond-range points.
InsertionReport to_measurements(PointSpan points, const GridGeometry& g, const SensorModel& model, int threads,
                                MeasurementChunks& measurements);

/// Splits the tile rows into `parts` bands of about equal work (column updates), so that neither thread
/// waits for the other where the scene is uneven (floor below, far wall or no returns above). Returns
/// parts + 1 tile-row boundaries. Any split gives the same result: each column has one owner.
std::vector<int> balanced_bands(const MeasurementChunks& measurements, int tile_rows, int parts);

}  // namespace occ_improve::detail
