"""Segmentation along negative-improvement contours (tests/test_segmentation.cpp through Python)."""
import numpy as np
import pytest

import occ_improve as oi
from conftest import data_file


def label_at(mapper, segmentation, point):
    located = mapper.locate(point)
    assert located is not None, point
    azimuth_bin, elevation_bin = located
    return int(segmentation.label[elevation_bin, azimuth_bin])


@pytest.fixture
def sample_mapper(sample):
    """The built-in sample in a kinect_v1 map, and the segmentation defaults for it."""
    depth, intrinsics = sample
    preset = oi.kinect_v1(intrinsics)
    mapper = oi.Mapper(preset)
    mapper.insert_depth(depth, intrinsics)
    return mapper, oi.segmentation_defaults(preset)


def test_segment_without_params_uses_the_tools_defaults():
    """Mapper.segment() took the generic SegmentationParams() (a 10 mm plane band) where occ_segment takes
    segmentation_defaults (6 mm, pixel-native): 793 rays of mOSD learn0 were labelled otherwise."""
    cloud = oi.read_pcd(data_file("segmentation/mosd_learn/learn0.pcd"))
    preset = oi.kinect_v1(oi.fit_intrinsics(cloud.points).intrinsics)
    mapper = oi.Mapper(preset)
    mapper.insert(cloud.points)
    tools = oi.segmentation_defaults(preset)
    assert tools.plane_distance_m == pytest.approx(0.006) != oi.SegmentationParams().plane_distance_m
    default = mapper.segment().label
    assert np.array_equal(default, mapper.segment(tools).label)
    assert np.count_nonzero(default != mapper.segment(oi.SegmentationParams()).label) > 100
    # The paper preset's constant sigma takes the lower contour bar, decided by its noise model.
    assert oi.segmentation_defaults(oi.kinect_v1_paper()).contour_improvement_below == pytest.approx(-0.01)


def test_occluders_are_cut_from_the_background(sample_mapper):
    mapper, params = sample_mapper
    assert params.remove_dominant_plane and oi.SegmentationParams().remove_dominant_plane  # the tools' default
    s = mapper.segment(params)
    box, pole = label_at(mapper, s, (-0.6, 0.45, 1.6)), label_at(mapper, s, (0.4, -0.5, 2.3))
    wall, floor = label_at(mapper, s, (-2.0, -1.0, 4.2)), label_at(mapper, s, (0.0, 0.8, 3.0))
    assert 0 not in (box, pole, wall, floor)
    assert box != wall and pole != wall
    assert s.contour_columns > 0 and s.contour.sum() == s.contour_columns
    labelled = np.count_nonzero(s.label)
    assert labelled == s.valid_columns == sum(seg.columns for seg in s.segments)
    assert [seg.label for seg in s.segments] == list(range(1, len(s.segments) + 1))
    assert any(seg.plane for seg in s.segments) and s.plane_columns > 0
    colours = oi.render_segmentation(s)
    assert colours.shape == (mapper.height, mapper.width, 3) and colours.dtype == np.uint8
    assert np.all(colours[s.label == 0] == 0) and np.all(colours[s.label != 0].max(axis=1) > 0)


def test_label_views_outlive_their_segmentation(paper_mapper):
    label = paper_mapper.segment().label
    assert label.dtype == np.uint32 and not label.flags.writeable
    assert np.count_nonzero(label) > 0  # the Segmentation was freed from Python, the view keeps it


def test_empty_map_gives_no_segments_and_bad_params_raise():
    empty = oi.Mapper(oi.kinect_v1_paper())
    assert empty.segment().segments == []
    with pytest.raises(oi.InvalidParameter, match="contour_improvement_below"):
        empty.segment(oi.SegmentationParams(contour_improvement_below=0.1))
    with pytest.raises(oi.InvalidParameter):
        oi.SegmentationParams(min_segment_columns=0).validate()


def test_thread_count_is_a_setting_that_does_not_change_the_result(sample_mapper):
    mapper, params = sample_mapper
    assert params.threads == 0  # every hardware thread, as the insertion's default
    params.threads = 1
    one = mapper.segment(params)
    params.threads = 2
    two = mapper.segment(params)
    assert one.valid_columns > 0
    assert np.array_equal(one.label, two.label) and np.array_equal(one.crease, two.crease)
    with pytest.raises(oi.InvalidParameter, match="threads"):
        oi.SegmentationParams(threads=-1).validate()
