// Saving and loading maps, and the OctoMap export where the module was built with it.
#include "arrays.hpp"
#include "bindings.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/geometry/rotation.hpp"
#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/io/map_io.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <Eigen/Geometry>

#include <cstring>
#include <string>

#ifdef OCC_IMPROVE_PYTHON_WITH_OCTOMAP
#include "occ_improve/octomap/export.hpp"
#endif

namespace occ_improve::python {
namespace {

/// Accepts str and os.PathLike (pathlib.Path), as Python's own file functions do.
std::string path_string(const py::object& path) {
  // os.fsencode: str, bytes and os.PathLike, as open() takes them (str() of bytes would be "b'...'"), as the
  // file system's bytes: a name that is not UTF-8 (b'\xff.occmap', or a str holding its surrogate escapes)
  // raised UnicodeEncodeError through fsdecode and a UTF-8 str.
  const std::string p = py::bytes(py::module_::import("os").attr("fsencode")(path));
  if (p.find('\0') != std::string::npos)  // C++ would stop at it: another file than the one named
    throw InvalidParameter("path " + std::string(py::repr(path)) + " holds a NUL character");
  return p;
}

/// LZF decompression (liblzf's format, as PCL's binary_compressed PCD data uses it), so that the
/// package reads those files without PCL: exactly `expected_bytes` must come out, every back reference
/// must stay inside what was already decoded, else FormatError. Runs without the GIL.
std::string lzf_decompress(const std::string& in, std::size_t expected_bytes) {
  std::string out(expected_bytes, '\0');
  const auto* ip = reinterpret_cast<const unsigned char*>(in.data());
  const auto* const in_end = ip + in.size();
  auto* const out_start = reinterpret_cast<unsigned char*>(out.data());
  unsigned char* op = out_start;
  unsigned char* const out_end = out_start + expected_bytes;
  const auto corrupt = [](const char* why) { throw FormatError(std::string("LZF data corrupt: ") + why); };
  while (ip < in_end) {
    std::size_t ctrl = *ip++;
    if (ctrl < (1u << 5)) {  // a run of ctrl + 1 literal bytes
      ++ctrl;
      if (ctrl > static_cast<std::size_t>(out_end - op)) corrupt("more bytes than declared");
      if (ctrl > static_cast<std::size_t>(in_end - ip)) corrupt("a literal run past the end of the input");
      std::memcpy(op, ip, ctrl);
      op += ctrl;
      ip += ctrl;
      continue;
    }
    std::size_t length = ctrl >> 5;  // a back reference: length + 2 bytes copied from `distance` bytes back
    if (ip >= in_end) corrupt("a back reference cut short");
    if (length == 7) {
      length += *ip++;
      if (ip >= in_end) corrupt("a back reference cut short");
    }
    const std::size_t distance = ((ctrl & 0x1f) << 8) + *ip++ + 1;
    const std::size_t bytes = length + 2;
    if (bytes > static_cast<std::size_t>(out_end - op)) corrupt("more bytes than declared");
    if (distance > static_cast<std::size_t>(op - out_start)) corrupt("a back reference before the start");
    if (distance >= bytes) {
      std::memcpy(op, op - distance, bytes);
    } else {  // the copy overlaps what it writes (a run): byte by byte, as the format means it
      const unsigned char* from = op - distance;
      for (std::size_t i = 0; i < bytes; ++i) op[i] = from[i];
    }
    op += bytes;
  }
  if (op != out_end) corrupt("fewer bytes than declared");
  return out;
}

/// As the tools' -save and occ_to_octomap -o (OutputFile): an existing file is replaced only when occ_improve
/// wrote it (`is_own`, by its magic) or with overwrite=True, never when it has no write permission bit; a
/// symbolic link is written through; a folder, pipe or device is refused.
OutputFile output_file(const std::string& path, const char* flag, bool overwrite, bool (*is_own)(const std::string&),
                       const char* kind) {
  return OutputFile(path, flag, overwrite, is_own, kind, "pass overwrite=True");
}

// A pose arrives as a numpy array, not through pybind11's Eigen caster: GCC 12 gives a false
// maybe-uninitialized warning inside that caster for fixed-size matrices.
using PoseArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// A 4 x 4 rigid transform (its last row 0 0 0 1, its rotation within kRotationTolerance of one: the
/// nearest rotation is kept), or InvalidParameter naming `name`.
Eigen::Isometry3d rigid_pose(const PoseArray& m, const char* name) {
  if (m.ndim() != 2 || m.shape(0) != 4 || m.shape(1) != 4)
    throw InvalidParameter(std::string(name) + " must be a 4 x 4 matrix");
  Eigen::Matrix4d t;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) t(r, c) = m.at(r, c);
  const std::optional<Eigen::Isometry3d> pose = rigid_transform(t);
  if (!pose)
    throw InvalidParameter(std::string(name) + " is not a rigid transform (a rotation, a finite translation, last row 0 0 0 1)");
  return *pose;
}

// Read-only: `mapper.world_from_sensor[0, 3] += 1` on a writable copy did nothing without a word; assign
// the whole matrix instead.
py::array_t<double> pose_array(const Eigen::Isometry3d& pose) {
  py::array_t<double> a({4, 4});
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) a.mutable_at(r, c) = pose.matrix()(r, c);
  make_read_only(a);
  return a;
}

/// The pose a call uses: `given` when there is one, else the Mapper's own (set by load_map or assigned).
std::optional<Eigen::Isometry3d> pose_or_mappers(const PyMapper& self, const std::optional<PoseArray>& given) {
  if (given) return rigid_pose(*given, "world_from_sensor");
  return self.world_from_sensor;
}

void bind_map_io(py::module_& m, py::class_<PyMapper>& c) {
  m.attr("MAP_FORMAT_VERSION") = kMapFormatVersion;
  c.def_property(
      "world_from_sensor",
      [](const PyMapper& self) -> py::object {
        if (!self.world_from_sensor) return py::none();
        return pose_array(*self.world_from_sensor);
      },
      [](PyMapper& self, const std::optional<PoseArray>& pose) {
        self.world_from_sensor = pose ? std::optional<Eigen::Isometry3d>(rigid_pose(*pose, "world_from_sensor")) : std::nullopt;
      },
      "Where the map's sensor frame lies in the world (4 x 4 float64, a read-only copy: assign a whole matrix "
      "to change it), or None: save() writes it with "
      "the map and load_map() reads it back, so that frames with poses of their own can be moved into the "
      "map's view after a load (inv(world_from_sensor) @ frame_pose); export_octomap() places the tree by it "
      "when given no pose. Assign a 4 x 4 rigid transform (InvalidParameter otherwise) or None.");
  c.def("save", [](PyMapper& self, const py::object& path, bool overwrite, const ReturnRecord* returns,
                   const std::optional<PoseArray>& world_from_sensor) {
    const std::string p = path_string(path);
    const std::optional<Eigen::Isometry3d> pose = pose_or_mappers(self, world_from_sensor);  // checked before the file
    OutputFile out = output_file(p, "save", overwrite, &is_map_file, "a map");
    with_mapper(self, [&](Mapper& mp) {
      save_map(out.staged(), mp.grid(), mp.model().params(), returns ? *returns : ReturnRecord(), pose);
    });
    out.commit();
  }, py::arg("path"), py::arg("overwrite") = false, py::arg("returns") = py::none(),
        py::arg("world_from_sensor") = py::none(),
        "Writes the grid and its sensor model (atomically: temp file + rename), with the planner's "
        "ReturnRecord when given (InvalidInput when it is of another grid) and the pose of the map's sensor "
        "frame: world_from_sensor when given (4 x 4 rigid transform), else the Mapper's world_from_sensor "
        "(None: no pose). An existing file is replaced when it is a map occ_improve wrote, or with "
        "overwrite=True; else IoError, and the file is kept. Raises IoError.");
  // Both loaders read the whole file; the record is what save(returns=...) wrote, else an empty one.
  const auto load = [](const py::object& path) {
    const std::string p = path_string(path);
    return run_interruptible([&] {
      LoadedMap loaded = load_map(p);
      return std::make_pair(std::make_unique<PyMapper>(Mapper(std::move(loaded.grid), SensorModel(loaded.model)),
                                                       loaded.world_from_sensor),
                            std::move(loaded.returns));
    });
  };
  m.def("load_map", [load](const py::object& path) { return std::move(load(path).first); }, py::arg("path"),
        "A Mapper continuing from a saved map (surface and improvement recomputed; its world_from_sensor the "
        "pose saved with it, else None). Raises IoError when "
        "the file cannot be read, FormatError when it is not a valid map.");
  m.def("load_map_and_returns", [load](const py::object& path) {
    auto [mapper, returns] = load(path);
    return py::make_tuple(std::move(mapper), std::move(returns));
  }, py::arg("path"),
        "(Mapper, ReturnRecord): load_map and the return record saved with the map (an empty record of the "
        "grid's size when none was saved), to continue a closed loop where it stopped.");
}

#ifdef OCC_IMPROVE_PYTHON_WITH_OCTOMAP
void bind_octomap(py::module_& m, py::class_<PyMapper>& c) {
  py::enum_<FreeLeafRule>(m, "FreeLeafRule", "Which OcTree leaves the export writes free.")
      .value("crossed", FreeLeafRule::crossed,
             "free space crosses the leaf (its centre or a corner), as OctoMap frees a leaf a ray crosses (default)")
      .value("wholly_free", FreeLeafRule::wholly_free, "the leaf lies wholly in free space: unknown space stays unknown");
  py::class_<OctomapExportOptions> o(m, "OctomapExportOptions",
                                     "Occupancy threshold, unknown band, free-leaf rule, memory cap.");
  def_value_struct<OctomapExportOptions>(o);
  o.def_readwrite("occupancy_threshold", &OctomapExportOptions::occupancy_threshold)
      .def_readwrite("unknown_band_probability", &OctomapExportOptions::unknown_band_probability)
      .def_readwrite("free_leaves", &OctomapExportOptions::free_leaves)
      .def_property("memory_cap_bytes", int_field_getter(&OctomapExportOptions::memory_cap_bytes),
                    int_field_setter(&OctomapExportOptions::memory_cap_bytes, "memory_cap_bytes"))
      .def("validate", &OctomapExportOptions::validate);
  py::class_<OctomapExportReport> r(m, "OctomapExportReport", "What the export wrote.");
  r.def_readonly("leaves_examined", &OctomapExportReport::leaves_examined)
      .def_readonly("occupied_written", &OctomapExportReport::occupied_written)
      .def_readonly("free_written", &OctomapExportReport::free_written)
      .def_readonly("left_unknown", &OctomapExportReport::left_unknown)
      .def_readonly("seconds", &OctomapExportReport::seconds);
  def_fields_repr(r, {"leaves_examined", "occupied_written", "free_written", "left_unknown", "seconds"});
  c.def("export_octomap", [](PyMapper& self, const py::object& path, double resolution_m,
                             const std::optional<PoseArray>& world_from_sensor, const OctomapExportOptions& options,
                             bool overwrite) {
    const std::string p = path_string(path);
    require_octomap_output_path(p);  // before any work, as the tools do
    OutputFile out = output_file(p, "export_octomap", overwrite, &is_octomap_file, "an OctoMap file");
    const Eigen::Isometry3d pose = pose_or_mappers(self, world_from_sensor).value_or(Eigen::Isometry3d::Identity());
    const OctomapExportReport written = with_mapper(self, [&](Mapper& mp) {
      OctomapExportReport report;
      const auto tree = to_octree(mp.grid(), pose, resolution_m, options, &report);
      write_octree(*tree, out.staged());
      return report;
    });
    out.commit();
    return written;
  }, py::arg("path"), py::arg("resolution_m"), py::arg("world_from_sensor") = py::none(),
        py::arg("options") = OctomapExportOptions{}, py::arg("overwrite") = false,
        "Writes the grid as an OctoMap .bt (maximum likelihood) or .ot (log-odds) file at resolution_m, "
        "seen from world_from_sensor (4 x 4 rigid transform; None: the Mapper's world_from_sensor, else the "
        "identity). An existing file is replaced "
        "when occ_improve wrote it, or with overwrite=True; else IoError before any work.");
}
#endif

}  // namespace

void bind_io(py::module_& m) {
  auto c = py::reinterpret_borrow<py::class_<PyMapper>>(m.attr("Mapper"));
  bind_map_io(m, c);
#ifdef OCC_IMPROVE_PYTHON_WITH_OCTOMAP
  m.attr("HAS_OCTOMAP") = true;
  bind_octomap(m, c);
#else
  m.attr("HAS_OCTOMAP") = false;
#endif
  m.def("_lzf_decompress", [](const py::bytes& data, std::size_t expected_bytes) {
    std::string in = data;
    const std::string out = run_interruptible([&] { return lzf_decompress(in, expected_bytes); });
    return py::bytes(out);
  }, py::arg("data"), py::arg("expected_bytes"),
        "LZF-decompresses exactly expected_bytes (the reader of binary_compressed PCD files); FormatError otherwise.");
}

}  // namespace occ_improve::python
