#!/usr/bin/env python3
"""Acquire frames from one viewpoint until more acquisition stops paying (the stop signal).

Each frame is fused into the map; after it, the best region says where to look next and the StopMonitor
says whether to go on: it stops when the absolute thresholds are met or when the total expected
improvement has fallen by less than 3% for 3 frames in a row. The frames are the built-in sample's static
sequence (new noise each frame), or with --seven-scenes the 50 real 7-Scenes frames (a slowly moving
camera, fused as if from one viewpoint, which is what a static-camera user would do with them).

    PYTHONPATH=build/python python3 samples/python/acquire_until_stop.py [--seven-scenes] [--max-frames 40]
"""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

import occ_improve as oi


def sample_frames(count: int):
    for seed in range(1, count + 1):
        yield oi.sample_depth(seed=seed)


def seven_scenes_frames(count: int):
    env = os.environ.get("OCC_IMPROVE_DATA_DIR")
    folder = (Path(env) if env else Path(__file__).resolve().parents[2].parent / "shared" / "data") / \
        "sequences" / "7scenes_redkitchen"
    k = oi.read_intrinsics(folder / "camera-intrinsics.txt")
    for path in sorted((folder / "frames").glob("frame-*.depth.png"))[:count]:
        yield oi.read_depth_png(path), k


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seven-scenes", action="store_true", help="real frames instead of the built-in sample")
    parser.add_argument("--max-frames", type=int, default=40)
    args = parser.parse_args()
    frames = seven_scenes_frames(args.max_frames) if args.seven_scenes else sample_frames(args.max_frames)
    mapper, monitor = None, oi.StopMonitor()
    for number, (depth, intrinsics) in enumerate(frames, 1):
        if mapper is None:
            preset = oi.kinect_v1(intrinsics) if args.seven_scenes else oi.kinect_v1_paper()
            mapper = oi.Mapper(preset)
        mapper.insert_depth(depth, intrinsics)
        regions = mapper.regions()
        signal = monitor.update(mapper, regions)
        look = ""
        if regions:
            best = regions[0]
            look = (f", look next at azimuth {math.degrees(best.centre_azimuth_rad):+.1f} deg, "
                    f"elevation {math.degrees(best.centre_elevation_rad):+.1f} deg")
        print(f"frame {number:2d}: total {signal.total_improvement:9.1f}{look}")
        if signal.stop:
            print(f"stop after {number} frames: {signal.reason}")
            return
    print(f"no stop within {args.max_frames} frames")


if __name__ == "__main__":
    main()
