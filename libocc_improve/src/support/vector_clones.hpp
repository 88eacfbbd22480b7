#pragma once
// OCC_IMPROVE_CLONES(target): compile a function twice, for `target` and for baseline x86-64, and let the
// loader pick the clone the CPU supports (GCC's target_clones, an ifunc: glibc on Linux): vector code
// without -march=native. Elsewhere (Clang, other systems or CPUs) the function is compiled once.
// The loops vectorise only with -fno-trapping-math (set on the files that use this in CMake); check with
// -fopt-info-vec.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define OCC_IMPROVE_CLONES(target) __attribute__((target_clones(target, "default")))
#else
#define OCC_IMPROVE_CLONES(target)
#endif
