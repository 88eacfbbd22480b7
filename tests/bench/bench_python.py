#!/usr/bin/env python3
"""What a full 640x480 frame costs through Python against the same calls made from C++.

Per frame, on one Mapper: insert the frame's points (N x 3 float32, read in place), find the regions,
copy the improvement map out. The C++ side is the module's _reference_frame_seconds, which makes those
calls in C++ on the same arrays with the same library build, so the difference is the binding's cost
(argument conversion, GIL release, the Mapper's lock, result conversion). Rounds alternate Python and
C++, and the figure is the ratio of median round times, because the machine is shared.

    make python-bench        (or: PYTHONPATH=build/python python3 tests/bench/bench_python.py)
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


def python_round(preset: oi.SensorPreset, frames, threads: int):
    mapper = oi.Mapper(preset)
    seconds = []
    for points in frames:
        start = time.perf_counter()
        mapper.insert(points, threads=threads)
        mapper.regions()
        mapper.improvement()
        seconds.append(time.perf_counter() - start)
    return seconds


def measure(preset, frames, rounds: int, threads: int):
    python, cpp = [], []
    for r in range(rounds):
        # Alternate which side goes first so that a slow spell on the shared machine hits both.
        if r % 2 == 0:
            python.append(sum(python_round(preset, frames, threads)))
            cpp.append(sum(oi._reference_frame_seconds(preset, frames, threads)))
        else:
            cpp.append(sum(oi._reference_frame_seconds(preset, frames, threads)))
            python.append(sum(python_round(preset, frames, threads)))
    return python, cpp


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=5, help="frames per round")
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--threads", type=int, default=0, help="insertion threads (0: all cores)")
    parser.add_argument("--preset", default="kinect_v1_paper", choices=oi.preset_names())
    args = parser.parse_args()
    preset = oi.preset_by_name(args.preset)
    frames = sample_frames(args.frames)
    python_round(preset, frames[:1], args.threads)  # warm-up: first-touch allocations, caches
    python, cpp = measure(preset, frames, args.rounds, args.threads)
    per_frame = lambda xs: statistics.median(xs) / len(frames) * 1e3  # noqa: E731
    overhead = statistics.median(python) / statistics.median(cpp) - 1
    best = min(python) / min(cpp) - 1
    print(f"preset {args.preset}, {len(frames)} frames of {frames[0].shape[0]} points per round, "
          f"{args.rounds} rounds, threads={args.threads}")
    print(f"  C++    : {per_frame(cpp):8.2f} ms per frame (median round)")
    print(f"  Python : {per_frame(python):8.2f} ms per frame (median round)")
    print(f"  overhead: {overhead * 100:+.2f}% of median rounds, {best * 100:+.2f}% of best rounds (target <= 5%)")


if __name__ == "__main__":
    main()
