"""Real Kinect frames from ../shared/data (skipped with a message where absent): 7-Scenes and TUM depth
PNGs through Python, checked against the counts, against each other and against the C++ tool."""
import os
import subprocess

import numpy as np
import pytest

import occ_improve as oi
from conftest import assert_same_maps, data_file

pytest.importorskip("PIL", reason="reading depth PNGs needs Pillow (Debian: python3-pil)")

KITCHEN = "sequences/7scenes_redkitchen"


def kitchen_frame(index=150):
    depth = oi.read_depth_png(data_file(f"{KITCHEN}/frames/frame-{index:06d}.depth.png"))
    return depth, oi.read_intrinsics(data_file(f"{KITCHEN}/camera-intrinsics.txt"))


def test_seven_scenes_frame_is_read_and_fully_accounted_for():
    depth, k = kitchen_frame()
    assert depth.shape == (480, 640) and depth.dtype == np.float32
    assert (k.fx, k.fy, k.cx, k.cy) == (585, 585, 320, 240)
    valid = depth > 0
    # Kinect v1 quantisation: adjacent distinct depths ~3 mm apart at 1 m (data README).
    assert 0.5 < np.median(depth[valid]) < 5 and valid.mean() > 0.5
    mapper = oi.Mapper(oi.kinect_v1(k))
    r = mapper.insert_depth(depth, k).insertion
    assert r.points_received == depth.size and r.skipped_invalid == np.count_nonzero(~valid)
    assert r.skipped_outside_fov == 0 and r.points_inserted == np.count_nonzero(valid)
    improvement = mapper.improvement()
    assert np.isfinite(improvement).all()
    unknown = mapper.unknown()
    # No-return rays carry the no-data value; measured ones are worth less on average (the depth edges
    # and hole borders are negative).
    assert np.median(improvement[unknown]) == pytest.approx(0.324, abs=0.01)
    assert improvement[~unknown].mean() < improvement[unknown].mean() - 0.05
    d = mapper.depth()
    measured = ~unknown & (d > 0)
    assert measured.sum() > 0.8 * valid.sum()
    assert 0.5 < np.median(d[measured]) < 5


def test_raw_millimetres_and_metres_give_the_same_maps():
    depth, k = kitchen_frame()
    from PIL import Image
    raw = np.asarray(Image.open(data_file(f"{KITCHEN}/frames/frame-000150.depth.png"))).astype(np.uint16)
    a, b = oi.Mapper(oi.kinect_v1(k)), oi.Mapper(oi.kinect_v1(k))
    a.insert_depth(raw, k, scale=0.001)
    b.insert_depth((raw.astype(np.float64) * 0.001).astype(np.float32), k)
    assert_same_maps(a, b)
    np.testing.assert_allclose(depth, raw * 0.001, atol=1e-6)


def test_raw_millimetres_without_their_scale_and_the_nominal_camera_are_refused():
    """The PNG's uint16 millimetres with the default scale (or Open3D's depth_scale=1000) put every return
    beyond 8 m; the nominal Kinect v1 (fx = 525) is not the kitchen camera (fx = 585)."""
    _, k = kitchen_frame()
    from PIL import Image
    raw = np.asarray(Image.open(data_file(f"{KITCHEN}/frames/frame-000150.depth.png"))).astype(np.uint16)
    mapper = oi.Mapper(oi.kinect_v1(k))
    for scale in (1.0, 1000.0):
        with pytest.raises(oi.InvalidParameter, match=r"looks like millimetres: pass scale=0.001$") as e:
            mapper.insert_depth(raw, k, scale=scale)
        median_m = float(str(e.value).split(" at ")[1].split(" m,")[0])
        assert median_m == pytest.approx(np.median(raw[raw > 0]) * scale, rel=1e-5)
    with pytest.raises(oi.InvalidParameter, match=r"\(fx=525.00 .*\) are not the camera the grid was built for "
                                                  r"\(fx=585.00 fy=585.00 cx=320.00 cy=240.00 640x480\)"):
        mapper.insert_depth(raw, oi.kinect_v1_intrinsics(), scale=0.001)
    assert mapper.touched_columns() == 0
    r = mapper.insert_depth(raw, k, scale=0.001).insertion
    assert r.points_inserted == np.count_nonzero(raw) and r.skipped_outside_fov == 0


def test_a_short_sequence_lowers_the_improvement_frame_after_frame():
    """The camera moves ~5 mm per frame; from one viewpoint's grid, each frame still adds knowledge."""
    _, k = kitchen_frame()
    mapper, totals = oi.Mapper(oi.kinect_v1(k)), []
    for index in (150, 151, 152):
        mapper.insert_depth(kitchen_frame(index)[0], k)
        totals.append(mapper.stop_signal().total_improvement)
    assert totals[0] > totals[1] > totals[2]


def test_tum_frame_with_its_own_scale():
    path = data_file("formats/tum_fr2/ch7/1_depth.png")
    depth = oi.read_depth_png(path, scale=1 / 5000)
    k = oi.PinholeIntrinsics(fx=520.9, fy=521.0, cx=325.1, cy=249.7)
    mapper = oi.Mapper(oi.kinect_v1(k))
    r = mapper.insert_depth(depth, k).insertion
    assert r.points_inserted == np.count_nonzero(depth > 0) and r.skipped_outside_fov == 0
    assert 0.5 < np.median(depth[depth > 0]) < 6  # metres, so the scale was right
    assert len(mapper.regions()) > 0


def test_python_maps_equal_the_cpp_tools_maps(tmp_path):
    """The same frame through occ_improve_map (C++, PCL reader) and through Python."""
    tool = os.environ.get("OCC_IMPROVE_MAP_TOOL")
    if not tool or not os.access(tool, os.X_OK):
        pytest.skip("occ_improve_map not built (OCC_IMPROVE_MAP_TOOL unset): needs the PCL tools")
    frame = data_file(f"{KITCHEN}/frames/frame-000150.depth.png")
    intrinsics = data_file(f"{KITCHEN}/camera-intrinsics.txt")
    saved = tmp_path / "cpp.occmap"
    subprocess.run([tool, "-preset", "kinect_v1", "-intrinsics_file", str(intrinsics), "-depth_encoding", "mm",
                    str(frame), "-save", str(saved), "-o", str(tmp_path / "out")],
                   check=True, capture_output=True)
    cpp = oi.load_map(saved)
    depth, k = kitchen_frame()
    python = oi.Mapper(oi.kinect_v1(k))
    python.insert_depth(depth, k)
    assert cpp.geometry.depth_bins == python.geometry.depth_bins
    # Same decoding (mm * 0.001 in double, rounded to float once: read_depth_png here, insert_depth(mm,
    # scale=0.001) and the tool's depth_in_metres alike), same back-projection, same insertion: bit for bit.
    assert_same_maps(cpp, python)
