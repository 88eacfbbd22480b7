"""The pure-Python frame helpers: depth PNGs, intrinsics files, back-projection."""
import numpy as np
import pytest

import occ_improve as oi


def test_depth_png_round_trip_and_wrong_images(tmp_path):
    Image = pytest.importorskip("PIL.Image", reason="reading depth PNGs needs Pillow (Debian: python3-pil)")
    millimetres = (np.arange(480 * 640, dtype=np.uint32) % 60000).astype(np.uint16).reshape(480, 640)
    Image.fromarray(millimetres).save(tmp_path / "d.png")
    depth = oi.read_depth_png(tmp_path / "d.png")
    np.testing.assert_array_equal(depth, (millimetres * np.float32(0.001)).astype(np.float32))
    Image.fromarray(np.zeros((4, 4, 3), np.uint8)).save(tmp_path / "rgb.png")
    with pytest.raises(oi.InvalidInput, match="not a 16-bit grey depth image"):
        oi.read_depth_png(tmp_path / "rgb.png")
    with pytest.raises(oi.IoError, match="missing.png"):
        oi.read_depth_png(tmp_path / "missing.png")


def test_intrinsics_files_in_both_layouts(tmp_path):
    (tmp_path / "k3.txt").write_text("585 0 320\n0 586 240\n0 0 1\n")
    k = oi.read_intrinsics(tmp_path / "k3.txt")
    assert (k.fx, k.fy, k.cx, k.cy, k.width, k.height) == (585, 586, 320, 240, 640, 480)
    (tmp_path / "k6.txt").write_text("262.5 262.5 159.5 119.5 320 240")
    assert oi.read_intrinsics(tmp_path / "k6.txt").width == 320
    (tmp_path / "k5.txt").write_text("1 2 3 4 5")
    with pytest.raises(oi.InvalidInput, match="expected 4, 6 or 9 numbers, got 5"):
        oi.read_intrinsics(tmp_path / "k5.txt")
    (tmp_path / "bad.txt").write_text("-5 0 320 0 585 240 0 0 1")
    with pytest.raises(oi.InvalidParameter, match="fx"):
        oi.read_intrinsics(tmp_path / "bad.txt")
    with pytest.raises(OSError):
        oi.read_intrinsics(tmp_path / "none.txt")


def test_back_projection_matches_the_pinhole_model(sample):
    depth, k = sample
    points = oi.depth_to_points(depth, k)
    assert points.shape == (480, 640, 3) and points.dtype == np.float32
    v, u = 100, 500
    z = depth[v, u]
    assert z > 0
    np.testing.assert_allclose(points[v, u], [(u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z], rtol=1e-6)
    assert np.isnan(points[depth == 0]).all()
    with pytest.raises(oi.InvalidInput):
        oi.depth_to_points(depth[:10], k)
