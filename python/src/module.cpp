// The extension module occ_improve._core; the package occ_improve re-exports it (python/occ_improve).
#include "bindings.hpp"

PYBIND11_MODULE(_core, m) {
  using namespace occ_improve::python;
  m.doc() = "occ_improve: spherical occupancy grids and the improvement map (C++ core, pybind11).";
  bind_errors(m);  // first: every later binding may throw them
  register_exit_wait();
  bind_presets(m);
  bind_mapper(m);
  bind_analysis(m);
  bind_planner(m);
  bind_io(m);
  bind_internals(m);
  bind_prediction(m);
}
