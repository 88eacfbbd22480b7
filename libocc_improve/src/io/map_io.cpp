#include "occ_improve/io/map_io.hpp"

#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/rotation.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <type_traits>
#include <vector>

namespace occ_improve {
namespace {

// Layout constants (docs/MAP_FORMAT.md). The byte-order marker is written in the writer's native
// order: a reader of the other byte order sees 0x04030201 and refuses the file.
constexpr char kMagic[8] = {'O', 'C', 'C', 'I', 'M', 'A', 'P', '\0'};
constexpr std::uint32_t kByteOrderMarker = 0x01020304u;
constexpr std::uint32_t kByteOrderSwapped = 0x04030201u;
constexpr std::size_t kChecksumBytes = sizeof(std::uint64_t);
constexpr std::size_t kPreambleBytes = sizeof(kMagic) + 2 * sizeof(std::uint32_t);  // magic, marker, version

// Bytes a long pass over a map's bytes takes between stop polls (~20 ms of checksum or write): a 1.7 GB
// exact-mode map was saved whole, and only then was a Ctrl-C seen, 1-8 s after it.
constexpr std::size_t kBytesBetweenPolls = std::size_t{64} << 20;

// FNV-1a 64 over 8-byte words (then the tail bytes): one multiply per word instead of per byte, so
// that a one-frame map of ~100 MB is checked in tens of milliseconds. Defined by the format document.
std::uint64_t checksum(const char* data, std::size_t size) {
  constexpr std::uint64_t kOffset = 14695981039346656037ull, kPrime = 1099511628211ull;
  static_assert(kBytesBetweenPolls % 8 == 0, "the chunks keep the words' alignment");
  std::uint64_t h = kOffset;
  std::size_t i = 0;
  while (i + 8 <= size) {
    throw_if_stop_requested();
    for (const std::size_t chunk_end = std::min(size, i + kBytesBetweenPolls); i + 8 <= chunk_end; i += 8) {
      std::uint64_t word;
      std::memcpy(&word, data + i, 8);
      h = (h ^ word) * kPrime;
    }
  }
  for (; i < size; ++i) h = (h ^ static_cast<unsigned char>(data[i])) * kPrime;
  return h;
}

class Writer {
public:
  template <typename T>
  void put(T value) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values only");
    const std::size_t at = bytes_.size();
    bytes_.resize(at + sizeof(T));
    std::memcpy(bytes_.data() + at, &value, sizeof(T));
  }
  void put_floats(const float* values, std::size_t count) {
    const std::size_t at = bytes_.size();
    bytes_.resize(at + count * sizeof(float));
    if (count) std::memcpy(bytes_.data() + at, values, count * sizeof(float));
  }
  void reserve(std::size_t n) { bytes_.reserve(n); }
  std::vector<char>& bytes() { return bytes_; }

private:
  std::vector<char> bytes_;
};

class Reader {
public:
  Reader(const std::vector<char>& bytes, std::size_t end, const std::string& path)
      : bytes_(bytes), end_(end), path_(path) {}
  template <typename T>
  T get(const char* what) {
    T value;
    need(sizeof(T), what);
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  void get_floats(std::vector<float>& out, std::size_t n, const char* what) {
    if (n > (end_ - at_) / sizeof(float)) fail(std::string("truncated in ") + what);
    out.resize(n);
    if (n) std::memcpy(out.data(), bytes_.data() + at_, n * sizeof(float));
    at_ += n * sizeof(float);
  }
  std::size_t remaining() const { return end_ - at_; }
  [[noreturn]] void fail(const std::string& problem) const {
    throw FormatError("map '" + path_ + "': " + problem);
  }

private:
  void need(std::size_t n, const char* what) const {
    if (end_ - at_ < n) fail(std::string("truncated in ") + what);
  }
  const std::vector<char>& bytes_;
  std::size_t at_ = kPreambleBytes, end_;
  const std::string& path_;
};

std::vector<char> read_file(const std::string& path, std::size_t memory_cap_bytes) {
  throw_if_folder(path, "map");
  // A map is read by its size, which a pipe, socket or device has not; opening a pipe without a writer
  // would block for good (a Python thread loading one kept the interpreter from exiting).
  if (is_pipe_or_device(path))
    throw IoError("cannot read map '" + path + "': it is not a regular file (a pipe, socket or device)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open map '" + path + "' for reading");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw IoError("cannot determine the size of map '" + path + "' (not a regular file?)");
  if (static_cast<std::uint64_t>(size) > memory_cap_bytes)
    throw ResourceLimit("map '" + path + "' of " + std::to_string(size) + " bytes exceeds memory_cap_bytes = " +
                        std::to_string(memory_cap_bytes));
  in.seekg(0, std::ios::beg);
  std::vector<char> bytes(static_cast<std::size_t>(size));
  if (size > 0 && !in.read(bytes.data(), size)) throw IoError("cannot read map '" + path + "'");
  return bytes;
}

constexpr std::uint32_t kMaxBinningTagLength = 64;  // the registries' limit

// Depth binnings with a code (every version); since version 4 kDepthBinningTagged says the tag follows.
constexpr std::uint32_t kDepthBinningUniform = 0, kDepthBinningInverse = 1, kDepthBinningTagged = 2;

bool has_depth_code(const GeometryParams& g) {
  return g.depth_binning == DepthBinning::uniform || g.depth_binning == DepthBinning::inverse_depth;
}

// Version 3 holds the binnings it has a code for (angular: 0 spherical, 1 pinhole, no row elevations; depth:
// 0 uniform, 1 inverse_depth): such maps are written as version 3, byte for byte as before, so that older
// builds still read them.
// A map with a pose is version 5 (version 4's geometry, then the pose after the return record), so that
// maps without one stay readable by builds before it.
std::uint32_t version_for(const GeometryParams& g, bool with_pose) {
  if (with_pose) return 5u;
  const bool has_code = g.angular_binning == AngularBinning::spherical || g.angular_binning == AngularBinning::pinhole;
  return has_code && g.row_elevations_rad.empty() && has_depth_code(g) ? 3u : 4u;
}

void write_tag(Writer& w, const std::string& tag) {
  w.put<std::uint32_t>(static_cast<std::uint32_t>(tag.size()));
  for (char c : tag) w.put<char>(c);
}

std::string read_tag(Reader& r, const char* kind) {
  const auto length = r.get<std::uint32_t>("geometry");
  if (length == 0 || length > kMaxBinningTagLength)
    r.fail(std::string("bad ") + kind + " tag length " + std::to_string(length));
  std::string tag;
  for (std::uint32_t i = 0; i < length; ++i) tag += r.get<char>("geometry");
  return tag;
}

void write_depth_binning(Writer& w, const std::string& tag) {
  if (tag == DepthBinning::uniform) {
    w.put<std::uint32_t>(kDepthBinningUniform);
  } else if (tag == DepthBinning::inverse_depth) {
    w.put<std::uint32_t>(kDepthBinningInverse);
  } else {  // version 4 (version_for)
    w.put<std::uint32_t>(kDepthBinningTagged);
    write_tag(w, tag);
  }
}

std::string read_depth_binning(Reader& r, std::uint32_t version) {
  const auto code = r.get<std::uint32_t>("geometry");
  if (code == kDepthBinningUniform) return DepthBinning::uniform;
  if (code == kDepthBinningInverse) return DepthBinning::inverse_depth;
  if (code != kDepthBinningTagged || version < 4) r.fail("unknown depth binning code " + std::to_string(code));
  const std::string tag = read_tag(r, "depth binning");
  if (!is_registered_depth_binning(tag))
    r.fail("unknown depth binning '" + tag + "' (no depth binning of that tag is registered in this program)");
  return tag;
}

void write_geometry(Writer& w, const GeometryParams& g, std::uint32_t version) {
  w.put<std::int32_t>(g.azimuth_bins);
  w.put<std::int32_t>(g.elevation_bins);
  w.put<std::int32_t>(g.depth_bins);
  w.put<double>(g.azimuth_min_rad);
  w.put<double>(g.azimuth_max_rad);
  w.put<double>(g.elevation_min_rad);
  w.put<double>(g.elevation_max_rad);
  write_depth_binning(w, g.depth_binning);
  w.put<double>(g.depth_min_m);
  w.put<double>(g.depth_max_m);
  // Since version 2: the angular binning and the camera; since version 4 the binning as its registered
  // tag (length, characters) instead of a code, and after the camera the row elevations.
  if (version < 4) {
    w.put<std::uint32_t>(g.angular_binning == AngularBinning::spherical ? 0u : 1u);
  } else {
    write_tag(w, g.angular_binning);
  }
  w.put<std::uint32_t>(g.camera ? 1u : 0u);
  const PinholeIntrinsics k = g.camera.value_or(PinholeIntrinsics{});
  for (double v : {k.fx, k.fy, k.cx, k.cy}) w.put<double>(v);
  w.put<std::int32_t>(k.width);
  w.put<std::int32_t>(k.height);
  if (version < 4) return;
  w.put<std::uint32_t>(static_cast<std::uint32_t>(g.row_elevations_rad.size()));
  for (double phi : g.row_elevations_rad) w.put<double>(phi);
}

// Versions 2-3 name the binning by a code: 0 spherical, 1 pinhole.
std::string read_binning_tag(Reader& r, std::uint32_t version) {
  if (version < 4) {
    const auto code = r.get<std::uint32_t>("geometry");
    if (code > 1) r.fail("unknown angular binning code " + std::to_string(code));
    return code == 0 ? AngularBinning::spherical : AngularBinning::pinhole;
  }
  const std::string tag = read_tag(r, "angular binning");
  if (!is_registered_angular_binning(tag))
    r.fail("unknown angular binning '" + tag + "' (no binning of that tag is registered in this program)");
  return tag;
}

// Version 1 maps are spherical grids without a camera.
void read_binning(Reader& r, GeometryParams& g, std::uint32_t version) {
  g.angular_binning = read_binning_tag(r, version);
  const auto has_camera = r.get<std::uint32_t>("geometry");
  if (has_camera > 1) r.fail("bad camera flag " + std::to_string(has_camera));
  PinholeIntrinsics k;
  k.fx = r.get<double>("geometry");
  k.fy = r.get<double>("geometry");
  k.cx = r.get<double>("geometry");
  k.cy = r.get<double>("geometry");
  k.width = r.get<std::int32_t>("geometry");
  k.height = r.get<std::int32_t>("geometry");
  if (has_camera) g.camera = k;
  if (version < 4) return;
  const auto rows = r.get<std::uint32_t>("geometry");
  if (rows > r.remaining() / sizeof(double)) r.fail("truncated in geometry");
  g.row_elevations_rad.resize(rows);
  for (double& phi : g.row_elevations_rad) phi = r.get<double>("geometry");
}

GeometryParams read_geometry(Reader& r, std::uint32_t version) {
  GeometryParams g;
  g.azimuth_bins = r.get<std::int32_t>("geometry");
  g.elevation_bins = r.get<std::int32_t>("geometry");
  g.depth_bins = r.get<std::int32_t>("geometry");
  g.azimuth_min_rad = r.get<double>("geometry");
  g.azimuth_max_rad = r.get<double>("geometry");
  g.elevation_min_rad = r.get<double>("geometry");
  g.elevation_max_rad = r.get<double>("geometry");
  g.depth_binning = read_depth_binning(r, version);
  g.depth_min_m = r.get<double>("geometry");
  g.depth_max_m = r.get<double>("geometry");
  if (version >= 2) read_binning(r, g, version);
  return g;
}

void write_model(Writer& w, const SensorModelParams& m) {
  w.put<double>(m.sigma_azimuth_rad);
  w.put<double>(m.sigma_elevation_rad);
  w.put<double>(m.sigma_depth_m);
  w.put<double>(m.sigma_depth_per_m2);
  w.put<double>(m.sigma_depth_floor_m);
  w.put<double>(m.support_k);
  w.put<double>(m.sigma_u_px);  // since version 2
  w.put<double>(m.sigma_v_px);
}

SensorModelParams read_model(Reader& r, std::uint32_t version) {
  SensorModelParams m;
  m.sigma_azimuth_rad = r.get<double>("sensor model");
  m.sigma_elevation_rad = r.get<double>("sensor model");
  m.sigma_depth_m = r.get<double>("sensor model");
  m.sigma_depth_per_m2 = r.get<double>("sensor model");
  m.sigma_depth_floor_m = r.get<double>("sensor model");
  m.support_k = r.get<double>("sensor model");
  if (version >= 2) {
    m.sigma_u_px = r.get<double>("sensor model");
    m.sigma_v_px = r.get<double>("sensor model");
  }
  return m;
}

void write_options(Writer& w, const GridOptions& o) {
  w.put<std::uint32_t>(o.mode == UpdateMode::clamped ? 0u : 1u);
  w.put<double>(o.probability_min);
  w.put<double>(o.probability_max);
  w.put<std::uint64_t>(o.memory_cap_bytes);
}

GridOptions read_options(Reader& r) {
  GridOptions o;
  const auto mode = r.get<std::uint32_t>("grid options");
  if (mode > 1) r.fail("unknown update mode code " + std::to_string(mode));
  o.mode = mode == 0 ? UpdateMode::clamped : UpdateMode::exact;
  o.probability_min = r.get<double>("grid options");
  o.probability_max = r.get<double>("grid options");
  o.memory_cap_bytes = static_cast<std::size_t>(r.get<std::uint64_t>("grid options"));
  return o;
}

// Parameter checks reuse the library's own validation; a file that fails them is a corrupt file.
template <typename Check>
void validated(Reader& r, const char* section, Check check) {
  try {
    check();
  } catch (const InvalidParameter& e) {
    r.fail(std::string("invalid ") + section + ": " + e.what());
  }
}

void read_columns(Reader& r, ColumnGrid& grid) {
  const std::uint64_t count = r.get<std::uint64_t>("column count");
  const std::size_t columns = grid.geometry().column_count();
  const std::int32_t bins = grid.geometry().depth().bins();
  if (count > columns) r.fail("claims " + std::to_string(count) + " touched columns, the grid has " +
                              std::to_string(columns));
  const bool clamped = grid.clamped();
  const float lo = grid.log_odds_min(), hi = grid.log_odds_max();
  auto value_ok = [&](float v) { return std::isfinite(v) && (!clamped || (v >= lo && v <= hi)); };
  std::int64_t previous = -1;
  std::vector<float> window;
  for (std::uint64_t n = 0; n < count; ++n) {
    poll_stop(static_cast<std::size_t>(n));
    const auto index = r.get<std::uint32_t>("column record");
    const auto uniform_end = r.get<std::int32_t>("column record");
    const auto uniform_value = r.get<float>("column record");
    const auto window_length = r.get<std::uint32_t>("column record");
    const std::string where = "column " + std::to_string(index);
    if (index >= columns) r.fail(where + " is outside the grid's " + std::to_string(columns) + " columns");
    if (static_cast<std::int64_t>(index) <= previous) r.fail(where + " is out of order (columns must ascend)");
    previous = index;
    if (uniform_end < 0 || uniform_end > bins) r.fail(where + ": uniform_end " + std::to_string(uniform_end) +
                                                      " outside [0, " + std::to_string(bins) + "]");
    if (window_length > static_cast<std::uint32_t>(bins - uniform_end))
      r.fail(where + ": window of " + std::to_string(window_length) + " bins runs past the " +
             std::to_string(bins) + " depth bins");
    if (uniform_end == 0 && window_length == 0) r.fail(where + " is stored but holds nothing");
    if (uniform_end > 0 && !value_ok(uniform_value)) r.fail(where + ": uniform value out of range");
    r.get_floats(window, window_length, "column window");
    for (float v : window)
      if (!value_ok(v)) r.fail(where + ": window value out of range");
    grid.assign({index, uniform_end, uniform_value, window.data(), window_length});
  }
  grid.shrink_to_fit();  // columns came one by one: the tiles' storage grew geometrically
}

// Since version 3: a flag, then the columns ever asked for (ascending) with their asks and returns. A
// record without asks is none (it loads as the empty record of the grid's size either way): a map re-saved
// with the empty record a load gave it stays the bytes of one saved without.
void write_returns(Writer& w, const ReturnRecord& returns) {
  const bool any = returns.size() && returns.total_asked() > 0;
  w.put<std::uint32_t>(any ? 1u : 0u);
  if (!any) return;
  std::uint64_t asked_columns = 0;
  for (std::uint32_t a : returns.asked()) asked_columns += a ? 1 : 0;
  w.put<std::uint64_t>(asked_columns);
  for (std::size_t c = 0; c < returns.size(); ++c)
    if (returns.asked()[c]) {
      w.put<std::uint32_t>(static_cast<std::uint32_t>(c));
      w.put<std::uint32_t>(returns.asked()[c]);
      w.put<std::uint32_t>(returns.returned()[c]);
    }
}

ReturnRecord read_returns(Reader& r, const GridGeometry& g, std::uint32_t version) {
  const std::size_t columns = g.column_count();
  if (version < 3 || r.get<std::uint32_t>("return record") == 0) return ReturnRecord::for_grid(g.width(), g.height());
  const auto count = r.get<std::uint64_t>("return record");
  if (count > columns) r.fail("return record claims " + std::to_string(count) + " columns, the grid has " +
                              std::to_string(columns));
  std::vector<std::uint32_t> asked(columns, 0), returned(columns, 0);
  std::int64_t previous = -1;
  for (std::uint64_t n = 0; n < count; ++n) {
    const auto c = r.get<std::uint32_t>("return record");
    if (c >= columns || static_cast<std::int64_t>(c) <= previous)
      r.fail("return record column " + std::to_string(c) + " is outside the grid or out of order");
    previous = c;
    asked[c] = r.get<std::uint32_t>("return record");
    returned[c] = r.get<std::uint32_t>("return record");
  }
  try {
    return ReturnRecord::from_counts(g.width(), g.height(), std::move(asked), std::move(returned));
  } catch (const InvalidInput& e) {
    r.fail(std::string("invalid return record: ") + e.what());
  }
}

// Since version 5: the rotation row by row, then the translation [m].
void write_pose(Writer& w, const Eigen::Isometry3d& pose) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) w.put<double>(pose.linear()(i, j));
  for (int i = 0; i < 3; ++i) w.put<double>(pose.translation()(i));
}

std::optional<Eigen::Isometry3d> read_pose(Reader& r, std::uint32_t version) {
  if (version < 5) return std::nullopt;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = r.get<double>("pose");
  for (int i = 0; i < 3; ++i) m(i, 3) = r.get<double>("pose");
  const std::optional<Eigen::Isometry3d> pose = rigid_transform(m);
  if (!pose) r.fail("the pose is not a rigid motion (a rotation and a finite translation)");
  return pose;
}

}  // namespace

void save_map(const std::string& path, const ColumnGrid& grid, const SensorModelParams& model,
              const ReturnRecord& returns, const std::optional<Eigen::Isometry3d>& world_from_sensor) {
  const GridGeometry& geometry = grid.geometry();
  if (returns.size()) returns.check_matches(geometry.width(), geometry.height());
  std::optional<Eigen::Isometry3d> pose;
  if (world_from_sensor) {
    pose = rigid_transform(world_from_sensor->matrix());
    if (!pose) throw InvalidParameter("save_map: world_from_sensor is not a rigid motion (a rotation and a finite translation)");
  }
  Writer w;
  w.reserve(256 + grid.stored_voxel_count() * sizeof(float) + grid.touched_column_count() * 16);
  for (char c : kMagic) w.put<char>(c);
  w.put<std::uint32_t>(kByteOrderMarker);
  const std::uint32_t version = version_for(geometry.params(), pose.has_value());
  w.put<std::uint32_t>(version);
  write_geometry(w, geometry.params(), version);
  write_model(w, model);
  write_options(w, grid.options());

  std::vector<ColumnIndex> touched;
  for (std::size_t c = 0; c < geometry.column_count(); ++c) {
    const ColumnData* column = grid.find(static_cast<ColumnIndex>(c));
    if (column && column->touched()) touched.push_back(static_cast<ColumnIndex>(c));
  }
  w.put<std::uint64_t>(touched.size());
  for (std::size_t k = 0; k < touched.size(); ++k) {
    poll_stop(k);
    const ColumnIndex c = touched[k];
    const ColumnData& column = *grid.find(c);
    w.put<std::uint32_t>(c);
    w.put<std::int32_t>(column.uniform_end);
    w.put<float>(column.uniform_value);
    w.put<std::uint32_t>(static_cast<std::uint32_t>(column.window.size()));
    w.put_floats(column.window.data(), column.window.size());
  }
  write_returns(w, returns);
  if (pose) write_pose(w, *pose);
  std::vector<char>& bytes = w.bytes();
  w.put<std::uint64_t>(checksum(bytes.data(), bytes.size()));

  write_file_atomically(path, "map", [&](std::ostream& out) {
    for (std::size_t at = 0; at < bytes.size(); at += kBytesBetweenPolls) {
      throw_if_stop_requested();  // the temporary is removed, the previous file kept
      const std::size_t n = std::min(kBytesBetweenPolls, bytes.size() - at);
      if (!out.write(bytes.data() + at, static_cast<std::streamsize>(n))) return false;
    }
    return true;
  });
}

bool is_map_file(const std::string& path) {
  char magic[sizeof(kMagic)] = {};
  std::ifstream in(path, std::ios::binary);
  return in.read(magic, sizeof magic) && std::memcmp(magic, kMagic, sizeof kMagic) == 0;
}

LoadedMap load_map(const std::string& path, std::size_t memory_cap_bytes) {
  const std::vector<char> bytes = read_file(path, memory_cap_bytes);
  auto fail = [&](const std::string& problem) { throw FormatError("map '" + path + "': " + problem); };
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0)
    fail("not an occ_improve map (bad magic)");
  if (bytes.size() < kPreambleBytes + kChecksumBytes) fail("truncated header");
  std::uint32_t marker, version;
  std::memcpy(&marker, bytes.data() + sizeof(kMagic), sizeof(marker));
  std::memcpy(&version, bytes.data() + sizeof(kMagic) + sizeof(marker), sizeof(version));
  if (marker == kByteOrderSwapped) fail("written on a machine of the other byte order");
  if (marker != kByteOrderMarker) fail("bad byte-order marker");
  if (version < kOldestMapFormatVersion || version > kMapFormatVersion)
    fail("format version " + std::to_string(version) + ", this build reads versions " +
         std::to_string(kOldestMapFormatVersion) + " to " + std::to_string(kMapFormatVersion));
  const std::size_t body = bytes.size() - kChecksumBytes;
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + body, sizeof(stored));
  if (stored != checksum(bytes.data(), body)) fail("checksum mismatch (file truncated or corrupt)");

  Reader r(bytes, body, path);
  const GeometryParams geometry = read_geometry(r, version);
  const SensorModelParams model = read_model(r, version);
  GridOptions options = read_options(r);
  validated(r, "geometry", [&] { geometry.validate(); });
  validated(r, "sensor model", [&] { model.validate(); });
  validated(r, "grid options", [&] { options.validate(); });
  // The caller's cap, never the file's (a forged file would raise its own), before the geometry allocates.
  options.memory_cap_bytes = memory_cap_bytes;
  try {
    require_within_memory_cap(geometry, memory_cap_bytes);
  } catch (const ResourceLimit& e) {
    throw ResourceLimit("map '" + path + "': geometry: " + e.what());
  }
  // After the cap: a file claiming a huge grid is a ResourceLimit whatever its sigmas.
  validated(r, "sensor model", [&] { model.validate_for(geometry); });
  LoadedMap loaded{ColumnGrid(GridGeometry(geometry), options), model, {}, std::nullopt};
  read_columns(r, loaded.grid);
  loaded.returns = read_returns(r, loaded.grid.geometry(), version);
  loaded.world_from_sensor = read_pose(r, version);
  if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " unexpected bytes after the last record");
  return loaded;
}

}  // namespace occ_improve
