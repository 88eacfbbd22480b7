"""The Python sample and the benchmark's C++ reference run and produce what they promise."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import occ_improve as oi

ROOT = Path(__file__).resolve().parents[2]


def test_overlay_sample_writes_its_png(tmp_path):
    pytest.importorskip("matplotlib", reason="the sample draws with matplotlib (Debian: python3-matplotlib)")
    pytest.importorskip("PIL", reason="the sample reads depth PNGs with Pillow")
    env = dict(os.environ, MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, str(ROOT / "samples/python/improvement_overlay.py"), "--out", str(tmp_path)],
                         env=env, capture_output=True, text=True, check=True)
    png = tmp_path / "improvement_overlay.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20000
    assert "region 1:" in run.stdout and "wrote" in run.stdout


def test_benchmark_reference_times_every_frame():
    depth, intrinsics = oi.sample_depth()
    points = oi.depth_to_points(depth, intrinsics).reshape(-1, 3)
    cpp, python = oi.Mapper(oi.kinect_v1_paper()), oi.Mapper(oi.kinect_v1_paper())
    seconds = oi._core._reference_frame_seconds(cpp, [points, points[::2]], threads=1)
    assert len(seconds) == 2 and all(s > 0 for s in seconds)
    python.insert(points)
    python.insert(points[::2])
    np.testing.assert_array_equal(cpp.improvement(), python.improvement())  # the same work was timed
    with pytest.raises(oi.InvalidInput):
        oi._core._reference_frame_seconds(cpp, [np.zeros((3, 2), np.float32)])


def test_acquisition_loop_sample_stops_on_the_static_sequence():
    run = subprocess.run([sys.executable, str(ROOT / "samples/python/acquire_until_stop.py"), "--max-frames", "40"],
                         capture_output=True, text=True, check=True)
    last = run.stdout.strip().splitlines()[-1]
    assert last.startswith("stop after "), last
    assert 8 <= int(last.split()[2]) <= 35 and "look next at azimuth" in run.stdout
