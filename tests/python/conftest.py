"""Shared fixtures of the Python suite: the built-in sample and the real data in ../shared/data.

The data folder is found as the C++ tests find it: OCC_IMPROVE_DATA_DIR from the environment, else the
default CMake configured (OCC_IMPROVE_DATA_DIR_DEFAULT, set by ctest), else ../shared/data beside the
checkout. Tests that need a file skip with a message naming it where it is absent.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

import numpy as np
import pytest

import occ_improve as oi


def data_dir() -> Optional[Path]:
    chosen = os.environ.get("OCC_IMPROVE_DATA_DIR")  # when set, it alone decides, as in the C++ tests
    candidates = [chosen] if chosen else [os.environ.get("OCC_IMPROVE_DATA_DIR_DEFAULT"),
                                          str(Path(__file__).resolve().parents[2].parent / "shared" / "data")]
    for candidate in candidates:
        if candidate and Path(candidate).is_dir():
            return Path(candidate)
    return None


def data_file(relative: str) -> Path:
    """The file under the data folder, or a skip that says how to provide it."""
    root = data_dir()
    path = root / relative if root else None
    if path is None or not path.exists():
        pytest.skip(f"real data '{relative}' not found (set OCC_IMPROVE_DATA_DIR to the shared/data folder "
                    "to run this test)")
    return path


@pytest.fixture(scope="session")
def sample():
    """The built-in sample frame: (depth H x W float32 metres, intrinsics)."""
    return oi.sample_depth()


@pytest.fixture(scope="session")
def sample_points(sample):
    depth, intrinsics = sample
    return oi.depth_to_points(depth, intrinsics).reshape(-1, 3)


@pytest.fixture()
def paper_mapper(sample):
    mapper = oi.Mapper(oi.kinect_v1_paper())
    mapper.insert_depth(*sample)
    return mapper


def assert_same_maps(a: oi.Mapper, b: oi.Mapper) -> None:
    """Bit-for-bit equal surfaces and improvement maps."""
    np.testing.assert_array_equal(a.depth(), b.depth())
    np.testing.assert_array_equal(a.probability(), b.probability())
    np.testing.assert_array_equal(a.unknown(), b.unknown())
    np.testing.assert_array_equal(a.improvement(), b.improvement())
