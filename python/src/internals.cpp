// Underscore helpers, not API: the C++ side of `make python-bench` (the per-frame calls the benchmark
// makes from Python, timed in C++ in the same process, on the same arrays, with the same library build),
// and what the tests need to check that the documented input layouts are read in place.
#include "arrays.hpp"
#include "bindings.hpp"

#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/timing.hpp"

#include <pybind11/stl.h>

#include <ctime>

namespace occ_improve::python {
namespace {

/// Wall-clock seconds, or the calling thread's CPU seconds: with threads=1 the latter leaves out the time
/// the thread waited for a core, the main noise on a shared machine (Python: time.thread_time()).
double now_seconds(bool thread_cpu) {
  if (!thread_cpu) return occ_improve::now_seconds();
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Seconds per frame of: insert, regions, a copy of the improvement map; on `target`'s Mapper, so that
/// a benchmark can interleave these frames with the same frames through Python on another Mapper.
std::vector<double> reference_frames(PyMapper& target, const std::vector<py::object>& frames, int threads,
                                     bool thread_cpu) {
  std::vector<PointsInput> inputs;
  for (const py::object& f : frames) inputs.push_back(points_from_array(f));
  InsertionOptions options;
  options.threads = threads;
  return with_mapper(target, [&](Mapper& mapper) {
    std::vector<double> seconds;
    volatile float sink = 0;
    for (const PointsInput& in : inputs) {
      const double start = now_seconds(thread_cpu);
      mapper.insert(in.span, options);
      const auto regions = find_regions(mapper.geometry(), mapper.improvement(), mapper.surface());
      std::vector<float> improvement = mapper.improvement().value;
      seconds.push_back(now_seconds(thread_cpu) - start);
      sink = improvement.back() + static_cast<float>(regions.size());  // the copy may not be optimised away
    }
    (void)sink;
    return seconds;
  });
}

}  // namespace

void bind_internals(py::module_& m) {
  m.def("_reference_frame_seconds", &reference_frames, py::arg("mapper"), py::arg("frames"), py::arg("threads") = 0,
        py::arg("thread_cpu") = false,
        "Benchmark helper: per-frame seconds of Mapper.insert + regions() + improvement() made from C++ "
        "on this Mapper; thread_cpu=True: the calling thread's CPU time instead of wall time.");
  m.def("_points_read_in_place", [](const py::object& points) { return !points_from_array(points).copied; },
        py::arg("points"), "Test helper: whether Mapper.insert reads these points without a copy.");
  m.def("_depth_read_in_place", [](const py::object& depth, const PinholeIntrinsics& intrinsics) {
    return !depth_from_array(depth, intrinsics).copied;
  }, py::arg("depth"), py::arg("intrinsics"), "Test helper: whether Mapper.insert_depth reads this image without a copy.");
}

}  // namespace occ_improve::python
