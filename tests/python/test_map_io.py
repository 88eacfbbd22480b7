"""Saving and loading maps (tests/test_map_io.cpp through Python): exact round trips, errors."""
import os

import numpy as np
import pytest

import occ_improve as oi
from conftest import assert_same_maps


def test_round_trip_is_exact_and_mapping_continues_as_if_uninterrupted(tmp_path, paper_mapper):
    path = tmp_path / "scene.occmap"
    paper_mapper.save(path)
    loaded = oi.load_map(str(path))  # str and pathlib.Path both work
    assert_same_maps(loaded, paper_mapper)
    assert loaded.model.sigma_depth_m == paper_mapper.model.sigma_depth_m
    second = oi.sample_depth(seed=2)
    loaded.insert_depth(*second)
    paper_mapper.insert_depth(*second)
    assert_same_maps(loaded, paper_mapper)


def test_exact_mode_inverse_depth_preset_round_trips(tmp_path, sample):
    depth, intrinsics = sample
    preset = oi.kinect_v1(intrinsics)
    preset.geometry.depth_bins = 256  # exact mode updates every bin: fewer bins keep the test quick
    mapper = oi.Mapper(preset, oi.GridOptions(mode=oi.UpdateMode.exact))
    mapper.insert_depth(depth, intrinsics)
    mapper.save(tmp_path / "exact.occmap")
    loaded = oi.load_map(tmp_path / "exact.occmap")
    assert loaded.options.mode == oi.UpdateMode.exact
    assert loaded.geometry.depth_binning == oi.DepthBinning.inverse_depth
    assert_same_maps(loaded, mapper)


def test_missing_file_is_an_os_error_naming_it(tmp_path):
    missing = tmp_path / "nothing.occmap"
    with pytest.raises(oi.IoError, match="nothing.occmap") as e:
        oi.load_map(missing)
    assert isinstance(e.value, OSError)


def test_corrupt_or_foreign_files_are_format_errors(tmp_path, paper_mapper):
    foreign = tmp_path / "notes.occmap"
    foreign.write_bytes(b"this is not a map at all, just some text long enough to hold a header" * 4)
    with pytest.raises(oi.FormatError) as e:
        oi.load_map(foreign)
    assert isinstance(e.value, ValueError) and str(e.value)
    good = tmp_path / "good.occmap"
    paper_mapper.save(good)
    data = bytearray(good.read_bytes())
    data[len(data) // 2] ^= 0x10
    flipped = tmp_path / "flipped.occmap"
    flipped.write_bytes(bytes(data))
    with pytest.raises(oi.FormatError, match="checksum"):
        oi.load_map(flipped)
    truncated = tmp_path / "truncated.occmap"
    truncated.write_bytes(good.read_bytes()[:1000])
    with pytest.raises(oi.FormatError):
        oi.load_map(truncated)


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write into a read-only folder")
def test_unwritable_folder_is_an_io_error(tmp_path, paper_mapper):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        with pytest.raises(oi.IoError):
            paper_mapper.save(folder / "m.occmap")
    finally:
        folder.chmod(0o700)


def test_saving_into_a_missing_folder_is_an_io_error_and_leaves_nothing(tmp_path, paper_mapper):
    with pytest.raises(oi.IoError):
        paper_mapper.save(tmp_path / "no" / "such" / "folder" / "m.occmap")
    assert not (tmp_path / "no").exists()
    assert np.isfinite(paper_mapper.improvement()).all()


def test_save_replaces_its_own_map_but_not_a_users_file(tmp_path, paper_mapper):
    # save() replaced any file (a user's notes became a map); the tools' -save never did.
    notes = tmp_path / "notes.occmap"
    notes.write_text("my notes")
    with pytest.raises(oi.IoError, match="overwrite=True"):
        paper_mapper.save(notes)
    assert notes.read_text() == "my notes"
    own = tmp_path / "m.occmap"
    paper_mapper.save(own)
    paper_mapper.save(own)  # its own map is replaced
    assert own.read_bytes().startswith(b"OCCIMAP")
    paper_mapper.save(notes, overwrite=True)
    assert notes.read_bytes().startswith(b"OCCIMAP")
    assert oi.load_map(notes).width == paper_mapper.width


def test_save_keeps_read_only_files_pipes_and_links_as_the_tools_do(tmp_path, paper_mapper):
    """save() renamed over a read-only map (as root too) and blocked forever on a named pipe while reading
    its magic; the tools' -save refused both. A symbolic link is written through, as by the tools."""
    own = tmp_path / "kept.occmap"
    paper_mapper.save(own)
    before = own.read_bytes()
    own.chmod(0o444)
    for overwrite in (False, True):
        with pytest.raises(oi.IoError, match="read-only"):
            paper_mapper.save(own, overwrite=overwrite)
    assert own.read_bytes() == before and (own.stat().st_mode & 0o777) == 0o444
    fifo = tmp_path / "pipe.occmap"
    os.mkfifo(fifo)
    with pytest.raises(oi.IoError, match="not a regular file"):
        paper_mapper.save(fifo, overwrite=True)
    target = tmp_path / "target.occmap"
    paper_mapper.save(target)
    link = tmp_path / "link.occmap"
    link.symlink_to(target)
    paper_mapper.save(link)
    assert link.is_symlink() and oi.load_map(link).width == paper_mapper.width


def test_paths_whose_bytes_are_not_utf8_are_saved_loaded_and_named(tmp_path, paper_mapper):
    """open() takes b'\\xff.occmap'; save() raised UnicodeEncodeError, and an error naming such a path came
    without a message."""
    path = os.fsencode(tmp_path) + b"/\xff.occmap"
    paper_mapper.save(path)
    assert os.listdir(os.fsencode(tmp_path)) == [b"\xff.occmap"]
    assert oi.load_map(path).width == paper_mapper.width
    assert oi.load_map(os.fsdecode(path)).width == paper_mapper.width  # the same name as str (surrogates)
    with pytest.raises(oi.IoError, match=r"\\xfe-missing\.occmap"):
        oi.load_map(os.fsencode(tmp_path) + b"/\xfe-missing.occmap")


def test_a_return_record_saved_with_the_map_comes_back(tmp_path, sample):
    """The planner's record of asks and returns can be kept with the map (C++ save_map always could):
    a closed loop continues where it stopped."""
    depth, intrinsics = sample
    mapper = oi.Mapper(oi.kinect_v1(intrinsics))
    mapper.insert_depth(depth, intrinsics)
    record = oi.ReturnRecord.for_grid(mapper.width, mapper.height)
    record.record_shot([0, 1, 640 * 240 + 320], [False, True, True])
    mapper.save(tmp_path / "with.occmap", returns=record)
    loaded, returns = oi.load_map_and_returns(tmp_path / "with.occmap")
    assert np.array_equal(returns.asked, record.asked) and np.array_equal(returns.returned, record.returned)
    assert (returns.total_asked, returns.total_returned) == (3, 2)
    assert np.array_equal(loaded.improvement(), mapper.improvement())
    # Without a record: an empty one of the grid's size. A record of another grid is refused, nothing written.
    mapper.save(tmp_path / "without.occmap")
    _, none = oi.load_map_and_returns(tmp_path / "without.occmap")
    assert none.total_asked == 0 and none.asked.shape == (mapper.height, mapper.width)
    with pytest.raises(oi.InvalidInput):
        mapper.save(tmp_path / "other.occmap", returns=oi.ReturnRecord.for_grid(4, 3))
    assert not (tmp_path / "other.occmap").exists()



def test_the_pose_of_the_maps_view_is_saved_and_loaded_with_it(tmp_path, paper_mapper):
    """Frames with poses need the map's own pose to be placed in its view after a load (the tools' -load
    moved them into their first frame's view instead: a misaligned map, without a word)."""
    assert paper_mapper.world_from_sensor is None
    pose = np.eye(4)
    c, s = np.cos(0.4), np.sin(0.4)
    pose[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    pose[:3, 3] = [1.0, 2.0, -0.5]
    paper_mapper.save(tmp_path / "given.occmap", world_from_sensor=pose)
    loaded = oi.load_map(tmp_path / "given.occmap")
    assert np.allclose(loaded.world_from_sensor, pose, atol=1e-12)
    assert_same_maps(loaded, paper_mapper)
    # The Mapper's own pose is what save() writes when given none; it reads as a read-only copy (an in-place
    # change of a writable copy did nothing without a word): assign a whole matrix to change it.
    with pytest.raises(ValueError, match="read-only"):
        loaded.world_from_sensor[0, 3] = 99.0
    assert loaded.world_from_sensor[0, 3] == pytest.approx(1.0)
    loaded.save(tmp_path / "kept.occmap")
    assert np.allclose(oi.load_map(tmp_path / "kept.occmap").world_from_sensor, pose, atol=1e-12)
    loaded.world_from_sensor = None
    loaded.save(tmp_path / "none.occmap", overwrite=True)
    assert oi.load_map(tmp_path / "none.occmap").world_from_sensor is None
    # Not a rigid transform: refused, nothing written, the Mapper's pose unchanged.
    scaled = pose.copy()
    scaled[:3, :3] *= 2
    with pytest.raises(oi.InvalidParameter, match="rigid"):
        paper_mapper.save(tmp_path / "scaled.occmap", world_from_sensor=scaled)
    with pytest.raises(oi.InvalidParameter, match="rigid"):
        paper_mapper.world_from_sensor = scaled
    with pytest.raises(oi.InvalidParameter, match="4 x 4"):
        paper_mapper.world_from_sensor = np.eye(3)
    assert paper_mapper.world_from_sensor is None
    assert not (tmp_path / "scaled.occmap").exists()


def test_bytes_paths_are_file_names_and_a_nul_is_refused(tmp_path, paper_mapper):
    # os.fsdecode, as open() reads them: str() of bytes made a file named "b'...'".
    path = os.fsencode(tmp_path / "bytes.occmap")
    paper_mapper.save(path)
    assert sorted(os.listdir(tmp_path)) == ["bytes.occmap"]
    assert_same_maps(oi.load_map(path), paper_mapper)
    # C++ stops at a NUL: the path would name another file than the one given.
    with pytest.raises(oi.InvalidParameter, match="NUL"):
        paper_mapper.save(str(tmp_path / "victim.occmap") + "\0.suffix")
    with pytest.raises(oi.InvalidParameter, match="NUL"):
        oi.load_map(str(tmp_path / "bytes.occmap") + "\0anything")
    assert sorted(os.listdir(tmp_path)) == ["bytes.occmap"]
