"""The pure-Python frame helpers: depth PNGs, intrinsics files, back-projection."""
import numpy as np
import pytest

import occ_improve as oi
from conftest import assert_same_maps


def test_depth_png_round_trip_and_wrong_images(tmp_path):
    Image = pytest.importorskip("PIL.Image", reason="reading depth PNGs needs Pillow (Debian: python3-pil)")
    millimetres = (np.arange(480 * 640, dtype=np.uint32) % 60000).astype(np.uint16).reshape(480, 640)
    Image.fromarray(millimetres).save(tmp_path / "d.png")
    depth = oi.read_depth_png(tmp_path / "d.png")
    np.testing.assert_array_equal(depth, (millimetres * 0.001).astype(np.float32))  # in double, rounded once
    Image.fromarray(np.zeros((4, 4, 3), np.uint8)).save(tmp_path / "rgb.png")
    with pytest.raises(oi.InvalidInput, match="not a 16-bit grey depth image"):
        oi.read_depth_png(tmp_path / "rgb.png")
    with pytest.raises(oi.IoError, match="missing.png"):
        oi.read_depth_png(tmp_path / "missing.png")
    # Pillow widens a 32-bit signed TIFF to mode "I" as it does 16-bit PNGs: negative depths came back.
    Image.fromarray(np.full((4, 4), -1000, np.int32)).save(tmp_path / "negative.tif")
    with pytest.raises(oi.InvalidInput, match="negative.tif.*not a 16-bit grey depth image"):
        oi.read_depth_png(tmp_path / "negative.tif")


def test_a_depth_png_read_or_inserted_raw_gives_one_map(tmp_path, sample):
    """read_depth_png multiplied in float32 (float32(mm) * float32(0.001)), insert_depth(mm, scale=0.001)
    in double: 1 ulp apart on about half the pixels, so the two routes for one PNG built different maps."""
    Image = pytest.importorskip("PIL.Image", reason="reading depth PNGs needs Pillow (Debian: python3-pil)")
    depth, k = sample
    millimetres = np.round(depth * 1000).astype(np.uint16)
    Image.fromarray(millimetres).save(tmp_path / "d.png")
    read = oi.read_depth_png(tmp_path / "d.png")
    assert read.dtype == np.float32
    np.testing.assert_array_equal(read, (millimetres.astype(np.float64) * 0.001).astype(np.float32))
    via_png, via_raw = oi.Mapper(oi.kinect_v1(k)), oi.Mapper(oi.kinect_v1(k))
    via_png.insert_depth(read, k)
    via_raw.insert_depth(millimetres, k, scale=0.001)
    assert_same_maps(via_png, via_raw)
    tum = oi.read_depth_png(tmp_path / "d.png", scale=1 / 5000)  # any scale: the product is the double's
    np.testing.assert_array_equal(tum, (millimetres.astype(np.float64) / 5000).astype(np.float32))


@pytest.mark.parametrize("scale", [-1.0, 0.0, float("nan"), float("inf"), -0.001])
def test_depth_png_scale_must_be_finite_and_positive(tmp_path, scale):
    """A negative scale gave negative depths and NaN a frame of NaN, without a word; insert_depth
    refuses both naming scale."""
    Image = pytest.importorskip("PIL.Image", reason="reading depth PNGs needs Pillow (Debian: python3-pil)")
    Image.fromarray(np.full((4, 4), 1000, np.uint16)).save(tmp_path / "d.png")
    with pytest.raises(oi.InvalidParameter, match=r"scale = .* must be finite and > 0"):
        oi.read_depth_png(tmp_path / "d.png", scale=scale)
    with pytest.raises(oi.InvalidParameter, match=r"scale = .* must be finite and > 0"):
        oi.read_depth_png(tmp_path / "missing.png", scale=scale)  # checked before the file is read


def test_depth_png_claiming_gigapixels_is_invalid_input(tmp_path):
    # Pillow's DecompressionBombError escaped as a non-occ_improve exception.
    pytest.importorskip("PIL.Image", reason="reading depth PNGs needs Pillow (Debian: python3-pil)")
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", 100000, 100000, 16, 0, 0, 0, 0)
    (tmp_path / "huge.png").write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) +
                                        chunk(b"IDAT", zlib.compress(bytes(10))) + chunk(b"IEND", b""))
    with pytest.raises(oi.InvalidInput, match="huge.png"):
        oi.read_depth_png(tmp_path / "huge.png")


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
    # A fractional image size was cut to whole pixels without a word.
    (tmp_path / "fraction.txt").write_text("262.5 262.5 159.5 119.5 320.7 240")
    with pytest.raises(oi.InvalidInput, match="fraction.txt.*whole numbers, got 320.7 x 240"):
        oi.read_intrinsics(tmp_path / "fraction.txt")
    with pytest.raises(oi.InvalidInput, match="whole numbers"):
        oi.intrinsics_from_matrix(np.diag([525.0, 525.0, 1.0]), 640, 480.5)


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


class PinholeCameraIntrinsicStandIn:
    """The attributes of Open3D's o3d.camera.PinholeCameraIntrinsic (Open3D is not installed here):
    intrinsic_matrix a 3 x 3 float64 array, width and height ints."""

    def __init__(self, width, height, fx, fy, cx, cy):
        self.width, self.height = width, height
        self.intrinsic_matrix = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def test_intrinsics_from_a_camera_matrix():
    k = oi.intrinsics_from_matrix([[585.0, 0, 320.5], [0, 584.0, 240.25], [0, 0, 1]], 640, 480)
    assert (k.fx, k.fy, k.cx, k.cy, k.width, k.height) == (585.0, 584.0, 320.5, 240.25, 640, 480)
    # A K that is not a skew-free pinhole, or a bad value, is refused with what is wrong.
    with pytest.raises(oi.InvalidInput, match="3 x 3"):
        oi.intrinsics_from_matrix(np.eye(4), 640, 480)
    with pytest.raises(oi.InvalidInput, match="skew"):
        oi.intrinsics_from_matrix([[585.0, 2.0, 320], [0, 585, 240], [0, 0, 1]], 640, 480)
    with pytest.raises(oi.InvalidInput, match="skew"):
        oi.intrinsics_from_matrix([[585.0, 0, 320], [0, 585, 240], [0, 0, 2]], 640, 480)
    with pytest.raises(oi.InvalidParameter, match="fx"):
        oi.intrinsics_from_matrix([[-585.0, 0, 320], [0, 585, 240], [0, 0, 1]], 640, 480)
    # MATLAB's transposed K is named (the tools' intrinsics files follow the same rule), a complex K refused.
    with pytest.raises(oi.InvalidInput, match="looks transposed"):
        oi.intrinsics_from_matrix([[585.0, 0, 0], [0, 585, 0], [320, 240, 1]], 640, 480)
    with pytest.raises(TypeError, match="real"):
        oi.intrinsics_from_matrix(np.eye(3) * (585 + 1j), 640, 480)


def test_intrinsics_from_an_open3d_camera_build_the_same_grid(sample):
    depth, k = sample
    camera = PinholeCameraIntrinsicStandIn(k.width, k.height, k.fx, k.fy, k.cx, k.cy)
    from_o3d = oi.intrinsics_from_open3d(camera)
    assert (from_o3d.fx, from_o3d.fy, from_o3d.cx, from_o3d.cy) == (k.fx, k.fy, k.cx, k.cy)
    assert (from_o3d.width, from_o3d.height) == (k.width, k.height)
    # Accepted wherever the camera's intrinsics are: the preset from it takes the sample frame.
    a, b = oi.Mapper(oi.kinect_v1(from_o3d)), oi.Mapper(oi.kinect_v1(k))
    a.insert_depth(depth, from_o3d)
    b.insert_depth(depth, k)
    np.testing.assert_array_equal(a.improvement(), b.improvement())
    with pytest.raises(TypeError, match="intrinsic_matrix"):
        oi.intrinsics_from_open3d(k)  # a PinholeIntrinsics has no intrinsic_matrix


def test_intrinsics_file_with_a_skewed_matrix_names_the_file(tmp_path):
    path = tmp_path / "skewed.txt"
    path.write_text("585 1 320\n0 585 240\n0 0 1\n")
    with pytest.raises(oi.InvalidInput, match="skewed.txt.*skew"):
        oi.read_intrinsics(path)
