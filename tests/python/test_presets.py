"""Presets, parameters and errors (tests/test_presets.cpp through Python)."""
import math

import pytest

import occ_improve as oi


def test_paper_preset_has_the_papers_numbers():
    p = oi.kinect_v1_paper()
    g, m = p.geometry, p.model
    assert (g.azimuth_bins, g.elevation_bins, g.depth_bins) == (640, 480, 512)
    assert math.degrees(g.azimuth_max_rad - g.azimuth_min_rad) == pytest.approx(57.0, abs=1e-9)
    assert math.degrees(g.elevation_max_rad - g.elevation_min_rad) == pytest.approx(43.0, abs=1e-9)
    assert g.depth_max_m == 5.0 and g.depth_binning == oi.DepthBinning.uniform
    assert m.sigma_azimuth_rad ** 2 == pytest.approx(1.88e-7, abs=1e-12)
    assert m.sigma_depth_m ** 2 * 1e6 == pytest.approx(2.23e3, abs=1e-6)
    assert m.support_k == 2.0 and p.camera is None


def test_kinect_preset_is_built_from_its_intrinsics():
    k = oi.PinholeIntrinsics(fx=585, fy=585, cx=320, cy=240)
    p = oi.kinect_v1(k)
    assert p.camera is not None and p.camera.fx == 585
    assert p.geometry.depth_binning == oi.DepthBinning.inverse_depth
    assert p.model.sigma_depth_per_m2 > 0
    # Pixel-native: one column per pixel, sigma = one pixel's quantisation, a pixel lands in its own column.
    assert p.geometry.angular_binning == oi.AngularBinning.pinhole
    assert p.model.sigma_u_px == pytest.approx(1 / math.sqrt(12))
    mapper = oi.Mapper(p)
    for u, v in ((0, 0), (639, 0), (0, 479), (639, 479), (320, 240)):
        assert mapper.locate(((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0)) == (u, v)
    # The spherical variant keeps every pixel inside its grid too.
    s = oi.kinect_v1_spherical(k)
    assert s.geometry.angular_binning == oi.AngularBinning.spherical
    assert s.model.sigma_azimuth_rad == pytest.approx(1 / 585 / math.sqrt(12), abs=0.05 / 585)
    spherical = oi.Mapper(s)
    for u, v in ((0, 0), (639, 0), (0, 479), (639, 479), (320, 240)):
        assert spherical.locate(((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0)) is not None


def test_depth_binnings_are_tags():
    assert oi.DepthBinning.uniform == "uniform" and oi.DepthBinning.inverse_depth == "inverse_depth"
    assert {"uniform", "inverse_depth"} <= set(oi.registered_depth_binnings())
    g = oi.GeometryParams(depth_binning="inverse_depth", depth_min_m=0.5)
    g.validate()
    g.depth_binning = "no_such_binning"
    with pytest.raises(oi.InvalidParameter, match="depth_binning = 'no_such_binning'"):
        g.validate()


def test_lidar_rings_preset_rows_are_the_rings():
    p = oi.lidar_rings()  # a Velodyne VLP-16: 16 rings from -15 to +15 deg, 1800 azimuth steps
    assert p.geometry.angular_binning == oi.AngularBinning.lidar_rings == "lidar_rings"
    assert "lidar_rings" in oi.registered_angular_binnings()
    assert p.geometry.elevation_bins == 16 and p.geometry.azimuth_bins == 1800
    # Rows top to bottom in the optical frame (y down): the ring at +15 deg (up) first, at phi = -15 deg.
    assert p.geometry.row_elevations_rad[0] == pytest.approx(math.radians(-15))
    assert p.geometry.row_elevations_rad[-1] == pytest.approx(math.radians(15))
    mapper = oi.Mapper(p)
    up, right = math.radians(5), 0.001  # the ring at +5 deg (row 5), just right of straight ahead
    direction = (math.sin(right) * math.cos(up), -math.sin(up), math.cos(right) * math.cos(up))
    assert mapper.locate(direction) == (900, 5)
    with pytest.raises(oi.InvalidParameter, match=r"ring_elevations_deg\[2\]"):
        oi.lidar_rings(oi.LidarRingsOptions(ring_elevations_deg=[-1.0, 1.0, 0.5]))


def test_lookup_by_name_and_its_error():
    assert oi.preset_names() == ["kinect_v1", "kinect_v1_paper", "kinect_v1_spherical"]
    k = oi.PinholeIntrinsics(fx=585, fy=585, cx=320, cy=240)
    for name in oi.preset_names():
        preset = oi.preset_by_name(name, k)
        assert preset.name == name
        assert preset.camera is None if name == "kinect_v1_paper" else preset.camera.fx == 585
    assert oi.preset_by_name("kinect_v1_paper").geometry.depth_max_m == 5.0
    with pytest.raises(oi.InvalidParameter, match="known presets are kinect_v1, kinect_v1_paper, kinect_v1_spherical") as e:
        oi.preset_by_name("kinect_v9")
    assert isinstance(e.value, ValueError) and isinstance(e.value, oi.Error)


def test_camera_presets_never_assume_intrinsics():
    """kinect_v1 without intrinsics used to build a grid for fx = 525 silently; now the camera is required,
    and OpenNI's nominal Kinect v1 is asked for by name."""
    for preset in (oi.kinect_v1, oi.kinect_v1_spherical):
        with pytest.raises(TypeError, match="intrinsics"):
            preset()
    for name in ("kinect_v1", "kinect_v1_spherical"):
        with pytest.raises(oi.InvalidParameter, match=f"preset '{name}' is built from the depth camera's "
                                                      rf"intrinsics: call preset_by_name\('{name}', intrinsics\)"):
            oi.preset_by_name(name)
    nominal = oi.kinect_v1(oi.kinect_v1_intrinsics())
    assert (nominal.camera.fx, nominal.camera.cx, nominal.camera.width) == (525.0, 319.5, 640)


def test_bad_intrinsics_raise_invalid_parameter_naming_the_field():
    with pytest.raises(ValueError, match="fx"):
        oi.kinect_v1(oi.PinholeIntrinsics(fx=-1))
    with pytest.raises(oi.InvalidParameter, match="width"):
        oi.PinholeIntrinsics(width=0).validate()


def test_preset_from_pinhole_gives_one_column_per_pixel():
    k = oi.PinholeIntrinsics(fx=262.5, fy=262.5, cx=159.5, cy=119.5, width=320, height=240)
    p = oi.preset_from_pinhole(k, oi.PinholePresetOptions(depth_bins=256, depth_max_m=4.0), name="small")
    assert p.name == "small" and p.geometry.depth_bins == 256 and p.geometry.depth_max_m == 4.0
    mapper = oi.Mapper(p)
    assert (mapper.height, mapper.width) == (240, 320)
    assert mapper.improvement().shape == (240, 320)


def test_keyword_constructors_check_names_and_types():
    k = oi.PinholeIntrinsics(fx=500.0, width=320)
    assert (k.fx, k.fy, k.width, k.height) == (500.0, 525.0, 320, 480)
    with pytest.raises(TypeError, match="unexpected keyword argument 'fz'"):
        oi.PinholeIntrinsics(fz=1.0)
    with pytest.raises(TypeError):
        oi.PinholeIntrinsics(width="wide")
    assert "fx=500.0" in repr(k)


def test_grid_options_are_validated_by_the_mapper():
    assert oi.GridOptions.octomap_clamping().probability_min == pytest.approx(0.1192)
    with pytest.raises(oi.InvalidParameter, match="probability"):
        oi.Mapper(oi.kinect_v1_paper(), oi.GridOptions(probability_min=0.9, probability_max=0.6))
    tiny_cap = oi.GridOptions(memory_cap_bytes=1024)
    with pytest.raises(oi.ResourceLimit):
        oi.Mapper(oi.kinect_v1_paper(), tiny_cap)
    exact = oi.Mapper(oi.kinect_v1_paper(), oi.GridOptions(mode=oi.UpdateMode.exact))
    assert exact.options.mode == oi.UpdateMode.exact
