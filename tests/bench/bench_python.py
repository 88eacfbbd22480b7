#!/usr/bin/env python3
"""What a full 640x480 frame costs through Python against the same calls made from C++.

Per frame: insert the frame's points (N x 3 float32, read in place), find the regions, copy the
improvement map out. The C++ side is occ_improve._core._reference_frame_seconds, which makes those calls
in C++ (same arrays, same library build, timed inside C++) on a second Mapper fed the same frames, so the
difference is the binding's cost: argument conversion, GIL release, the Mapper's lock, result conversion.
The machine is shared, so each frame is run through both sides back to back (alternating which goes
first) and the figure is the median of the per-frame ratios, with the ratio of summed times beside it.
--cpu times the calling thread's CPU (single-threaded insertion) instead of the wall clock, which leaves
out the time spent waiting for a core: the steadiest figure on a busy machine.

    make python-bench        (wall time, all cores, then --cpu)
    PYTHONPATH=build/python python3 tests/bench/bench_python.py [--cpu] [--sequences N] [--preset kinect_v1]
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import occ_improve as oi


def sample_frames(count: int):
    """The built-in sample's static sequence as point arrays (noise seeds 1..count)."""
    frames = []
    for seed in range(1, count + 1):
        depth, intrinsics = oi.sample_depth(seed=seed)
        frames.append(np.ascontiguousarray(oi.depth_to_points(depth, intrinsics).reshape(-1, 3)))
    return frames


def python_frame(mapper: oi.Mapper, points: np.ndarray, threads: int, cpu: bool) -> float:
    clock = time.thread_time if cpu else time.perf_counter
    start = clock()
    mapper.insert(points, threads=threads)
    mapper.regions()
    mapper.improvement()
    return clock() - start


def cpp_frame(mapper: oi.Mapper, points: np.ndarray, threads: int, cpu: bool) -> float:
    return oi._core._reference_frame_seconds(mapper, [points], threads, cpu)[0]


def measure(preset, frames, sequences: int, threads: int, cpu: bool = False):
    """Paired per-frame times (python, cpp) over `sequences` runs of the frames on fresh Mappers."""
    pairs = []
    for s in range(sequences):
        py_mapper, cpp_mapper = oi.Mapper(preset), oi.Mapper(preset)
        for i, points in enumerate(frames):
            if (s + i) % 2 == 0:  # alternate which side goes first
                p = python_frame(py_mapper, points, threads, cpu)
                c = cpp_frame(cpp_mapper, points, threads, cpu)
            else:
                c = cpp_frame(cpp_mapper, points, threads, cpu)
                p = python_frame(py_mapper, points, threads, cpu)
            pairs.append((p, c))
    return pairs


def fixed_costs(preset) -> str:
    """The binding's own per-call costs, measured where the library has (almost) nothing to do."""
    mapper = oi.Mapper(preset)

    def per_call(f, n=2000):
        start = time.perf_counter()
        for _ in range(n):
            f()
        return (time.perf_counter() - start) / n * 1e6

    return (f"  per call: a Mapper method doing no work (GIL release + lock) {per_call(mapper.touched_columns):.1f} us, "
            f"improvement() copy {per_call(mapper.improvement, 300):.0f} us, "
            f"improvement(copy=False) {per_call(lambda: mapper.improvement(copy=False)):.1f} us")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=5, help="frames per sequence")
    parser.add_argument("--sequences", type=int, default=6)
    parser.add_argument("--threads", type=int, default=0, help="insertion threads (0: all cores)")
    parser.add_argument("--preset", default="kinect_v1_paper", choices=oi.preset_names())
    parser.add_argument("--cpu", action="store_true",
                        help="time the calling thread's CPU, not the wall clock (implies --threads 1): the time "
                             "spent waiting for a core on a busy machine is left out")
    args = parser.parse_args()
    if args.cpu:
        args.threads = 1  # other threads' CPU time would not be counted
    preset = oi.preset_by_name(args.preset, oi.sample_depth()[1])  # the camera presets for the sample's camera
    frames = sample_frames(args.frames)
    measure(preset, frames[:2], 1, args.threads, args.cpu)  # warm-up: first-touch allocations, caches
    pairs = measure(preset, frames, args.sequences, args.threads, args.cpu)
    python = [p for p, _ in pairs]
    cpp = [c for _, c in pairs]
    ratios = sorted(p / c - 1 for p, c in pairs)
    ratio = statistics.median(ratios)
    quartiles = statistics.quantiles(ratios, n=4)
    summed = sum(python) / sum(cpp) - 1
    print(f"preset {args.preset}, {len(pairs)} frames of {frames[0].shape[0]} points "
          f"({args.sequences} sequences of {len(frames)}), threads={args.threads}, "
          f"{'thread CPU time' if args.cpu else 'wall time'}")
    print(f"  C++    : {statistics.median(cpp) * 1e3:8.2f} ms per frame (median)")
    print(f"  Python : {statistics.median(python) * 1e3:8.2f} ms per frame (median)")
    print(f"  overhead: {ratio * 100:+.2f}% (median of per-frame ratios; quartiles {quartiles[0] * 100:+.1f}% .. "
          f"{quartiles[2] * 100:+.1f}%), {summed * 100:+.2f}% (summed times); target <= 5%")
    print(fixed_costs(preset))


if __name__ == "__main__":
    main()
