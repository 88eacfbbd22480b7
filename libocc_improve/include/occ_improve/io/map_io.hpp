#pragma once
// Saving and loading the spherical grid in a versioned binary format (docs/MAP_FORMAT.md): geometry,
// sensor model, update mode and clamping, the sparse column contents, and a checksum over all of it.
//
// save_map writes a temporary file beside the target and renames it over the target only once it is
// complete, so an interrupted save never leaves a half-written map under the real name.
// load_map verifies magic, byte order, version, size and checksum before it trusts any field, then
// checks every value against the geometry; it throws FormatError for a file that is not a valid map
// (naming what is wrong) and IoError for a file that cannot be opened or read. Round trips are exact:
// every voxel's log-odds comes back bit for bit.
#include "occ_improve/grid/grid.hpp"
#include "occ_improve/planning/return_model.hpp"
#include "occ_improve/sensor/sensor_model.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>

namespace occ_improve {

/// The newest format version this build writes. Version 2 added the angular binning and the camera,
/// version 3 the return record, version 4 the binning's registered tag (any binning, angular_binning.hpp)
/// and the row elevations, version 5 the pose of the map's sensor frame in the world (version 4's layout,
/// then the pose; written only for a map saved with one). Version 1 maps (spherical, no camera), version
/// 1-2 maps (no return record) and version 2-3 maps (binning code 0 spherical, 1 pinhole) still load.
constexpr std::uint32_t kMapFormatVersion = 5;
constexpr std::uint32_t kOldestMapFormatVersion = 1;

/// Writes `grid`, the sensor model it was built with, the return record of a selective sensor
/// (return_model.hpp; a default-constructed record: none) and, when known, `world_from_sensor`, where the
/// map's sensor frame (its viewpoint) lies in the world, to `path` (atomically: temp file + rename). The
/// pose is what lets frames with poses of their own be added to the map after a load: they are moved into
/// its sensor frame by it (the tools' -load). Throws IoError when the folder is not writable or the write
/// fails (the target is then untouched), InvalidInput when the record is not one of the grid's size,
/// InvalidParameter when the pose is not a rigid motion (a rotation within kRotationTolerance, taken as
/// the nearest one; finite); nothing is written then.
void save_map(const std::string& path, const ColumnGrid& grid, const SensorModelParams& model,
              const ReturnRecord& returns = ReturnRecord(),
              const std::optional<Eigen::Isometry3d>& world_from_sensor = std::nullopt);

/// Whether `path` starts with the map format's magic: a file save_map wrote (any version, perhaps corrupt).
/// What the tools check before they replace a file with -save (nothing else a user owns is replaced).
bool is_map_file(const std::string& path);

struct LoadedMap {
  ColumnGrid grid;
  SensorModelParams model;
  ReturnRecord returns;  ///< the saved record; an empty one of the grid's size when none was saved
  /// Where the map's sensor frame lies in the world; unset when it was saved without one (or before
  /// version 5).
  std::optional<Eigen::Isometry3d> world_from_sensor;
};

/// Reads a map written by save_map. Throws IoError (cannot open/read) or FormatError (not a map,
/// truncated, corrupt, other version, other byte order, inconsistent contents), ResourceLimit when the
/// file or the grid its geometry describes may exceed `memory_cap_bytes` (checked before allocating).
/// The loaded grid gets `memory_cap_bytes` as its cap: the cap stored in the file is not trusted, since
/// a forged file (the checksum is easy to recompute) would raise its own.
LoadedMap load_map(const std::string& path, std::size_t memory_cap_bytes = GridOptions{}.memory_cap_bytes);

}  // namespace occ_improve
