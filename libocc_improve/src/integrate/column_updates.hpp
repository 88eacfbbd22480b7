#pragma once
// Insertion, step 2 for one thread (private to src/integrate; integrate.cpp): the measurements added to
// the columns of one band of tile rows.
#include "integrate/measurements.hpp"

#include <cstddef>
#include <vector>

namespace occ_improve::detail {

/// Adds every measurement's truncated OPDF to the columns it overlaps in tile rows [first_tile_row,
/// end_tile_row) (`rows` lists each tile row's measurements), tile by tile, each column receiving its
/// measurements in input order. scratch_rows is the caller's buffer (kept from call to call). With a
/// surface, the band's columns' surfaces are kept current and those that changed are appended to
/// surface_changed. Returns the column updates.
std::size_t update_band(ColumnGrid& grid, const SensorModel& model, const MeasurementChunks& measurements,
                        const TileRows& rows, int first_tile_row, int end_tile_row, std::vector<float>& scratch_rows,
                        SurfaceMap* surface, std::vector<ColumnIndex>& surface_changed);

}  // namespace occ_improve::detail
