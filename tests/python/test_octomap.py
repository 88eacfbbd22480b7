"""OctoMap export where the module was built with it (tests/octomap through Python)."""
import numpy as np
import pytest

import occ_improve as oi

pytestmark = pytest.mark.skipif(not oi.HAS_OCTOMAP, reason="module built without the OctoMap adapter")


def small_mapper():
    """A 2 m depth range keeps the export fast at 5 cm."""
    preset = oi.kinect_v1_paper()
    preset.geometry.depth_max_m = 2.5
    depth, intrinsics = oi.sample_depth()
    mapper = oi.Mapper(preset)
    mapper.insert_depth(depth, intrinsics)
    return mapper


def test_bt_and_ot_files_are_written_with_occupied_and_free_space(tmp_path):
    mapper = small_mapper()
    report = mapper.export_octomap(tmp_path / "map.bt", 0.05)
    assert report.occupied_written > 0 and report.free_written > 0
    assert report.leaves_examined >= report.occupied_written + report.free_written + report.left_unknown
    assert (tmp_path / "map.bt").read_bytes().startswith(b"# Octomap OcTree binary file")
    pose = np.eye(4)
    pose[:3, 3] = (1.0, 2.0, 0.5)
    moved = mapper.export_octomap(tmp_path / "map.ot", 0.05, world_from_sensor=pose)
    assert (tmp_path / "map.ot").read_bytes().startswith(b"# Octomap OcTree file")
    # A translation moves the frustum across leaf boundaries: about, not exactly, as many leaves.
    assert moved.occupied_written == pytest.approx(report.occupied_written, rel=0.2)


def test_the_mappers_own_pose_places_the_tree_when_none_is_given(tmp_path):
    mapper = small_mapper()
    pose = np.eye(4)
    pose[:3, 3] = (1.0, 2.0, 0.5)
    mapper.export_octomap(tmp_path / "given.bt", 0.05, world_from_sensor=pose)
    mapper.export_octomap(tmp_path / "identity.bt", 0.05)
    mapper.world_from_sensor = pose  # as load_map sets it from a map saved with its pose
    mapper.export_octomap(tmp_path / "own.bt", 0.05)
    assert (tmp_path / "own.bt").read_bytes() == (tmp_path / "given.bt").read_bytes()
    assert (tmp_path / "own.bt").read_bytes() != (tmp_path / "identity.bt").read_bytes()


def test_free_leaves_rule_is_an_option(tmp_path):
    """crossed (the default) frees the leaves free space crosses, as OctoMap does; wholly_free fewer, no others."""
    mapper = small_mapper()
    crossed = mapper.export_octomap(tmp_path / "crossed.bt", 0.1)
    wholly = mapper.export_octomap(tmp_path / "wholly.bt", 0.1,
                                   options=oi.OctomapExportOptions(free_leaves=oi.FreeLeafRule.wholly_free))
    assert oi.OctomapExportOptions().free_leaves == oi.FreeLeafRule.crossed
    assert crossed.occupied_written == wholly.occupied_written
    assert crossed.free_written > 1.2 * wholly.free_written
    assert crossed.left_unknown < wholly.left_unknown


def test_export_prints_nothing(tmp_path, capfd):
    # liboctomap's own copy of writeBinaryData prints "Writing N nodes..." to stderr (its debug output).
    small_mapper().export_octomap(tmp_path / "map.bt", 0.05)
    assert capfd.readouterr() == ("", "")


def test_bad_extension_pose_and_resolution_raise_invalid_parameter(tmp_path):
    mapper = small_mapper()
    with pytest.raises(oi.InvalidParameter, match="txt"):
        mapper.export_octomap(tmp_path / "map.txt", 0.05)
    sheared = np.eye(4)
    sheared[0, 1] = 0.5
    with pytest.raises(oi.InvalidParameter):
        mapper.export_octomap(tmp_path / "map.bt", 0.05, world_from_sensor=sheared)
    with pytest.raises(oi.InvalidParameter):
        mapper.export_octomap(tmp_path / "map.bt", -1.0)
    assert not (tmp_path / "map.bt").exists()
    with pytest.raises(oi.ResourceLimit):
        mapper.export_octomap(tmp_path / "map.bt", 0.05, options=oi.OctomapExportOptions(memory_cap_bytes=1000))


def test_pose_must_be_a_4_by_4_matrix(tmp_path):
    with pytest.raises(oi.InvalidParameter, match="4 x 4"):
        small_mapper().export_octomap(tmp_path / "map.bt", 0.05, world_from_sensor=np.eye(3))


def test_export_replaces_its_own_tree_but_not_a_users_file(tmp_path):
    mapper = small_mapper()
    theirs = tmp_path / "theirs.bt"
    theirs.write_bytes(b"not a tree")
    with pytest.raises(oi.IoError, match="overwrite=True"):
        mapper.export_octomap(theirs, 0.05)
    assert theirs.read_bytes() == b"not a tree"
    own = tmp_path / "own.bt"
    mapper.export_octomap(own, 0.05)
    assert mapper.export_octomap(own, 0.05).occupied_written > 0  # its own tree is replaced
    mapper.export_octomap(theirs, 0.05, overwrite=True)
    assert theirs.read_bytes().startswith(b"# Octomap OcTree binary file")
    theirs.chmod(0o444)  # a protected file stays, overwrite=True or not (it was renamed over)
    before = theirs.read_bytes()
    with pytest.raises(oi.IoError, match="read-only"):
        mapper.export_octomap(theirs, 0.05, overwrite=True)
    assert theirs.read_bytes() == before
