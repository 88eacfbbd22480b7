"""docs/PYTHON.md's "What it offers" table names what the module offers: every function, every Mapper
method and property, every parameter struct and enum, and the mask= argument of the inserts."""
import re
from pathlib import Path

import pytest

import occ_improve as oi
from occ_improve import _core

PYTHON_MD = Path(__file__).resolve().parents[2] / "docs" / "PYTHON.md"


@pytest.fixture(scope="module")
def table():
    if not PYTHON_MD.is_file():
        pytest.skip(f"{PYTHON_MD} not found (the tests run outside a checkout)")
    return PYTHON_MD.read_text().split("## What it offers", 1)[1].split("\n## ", 1)[0]


def named(table, name):
    return re.search(rf"`[^`]*\b{re.escape(name)}\b[^`]*`", table) is not None


def test_every_function_struct_and_enum_is_in_the_table(table):
    """lidar_rings and LidarRingsOptions were left out."""
    functions = [n for n in dir(oi) if not n.startswith("_") and callable(getattr(oi, n))
                 and not isinstance(getattr(oi, n), type)]
    structs = [n for n, c in vars(_core).items() if isinstance(c, type)
               and ("**kwargs" in (c.__init__.__doc__ or "") or hasattr(c, "__members__"))]
    assert "lidar_rings" in functions and "LidarRingsOptions" in structs
    assert [n for n in functions + structs if not named(table, n)] == []


def test_every_mapper_method_and_property_is_in_the_table(table):
    """set_mask, clear_mask and column_mask were left out."""
    members = [n for n in vars(_core.Mapper) if not n.startswith("_")]
    if not oi.HAS_OCTOMAP:
        members.remove("export_octomap") if "export_octomap" in members else None
    assert {"set_mask", "clear_mask", "column_mask"} <= set(members)
    assert [n for n in members if not named(table, n)] == []


def test_the_mask_argument_of_the_inserts_is_in_the_table(table):
    """insert(..., mask=) and insert_depth(..., mask=) set a mask that stays for later inserts."""
    taking_mask = [n for n, f in vars(_core.Mapper).items() if not n.startswith("_") and callable(f)
                   and re.search(r"[(,] ?mask: [^,)]* = None", (f.__doc__ or "").split("\n", 1)[0])]
    assert set(taking_mask) == {"insert", "insert_depth"}
    rows = [line for line in table.splitlines() if "mask=" in line]
    assert all(any(f"{n}(" in row for row in rows) for n in taking_mask)
    assert any("later insert" in row for row in rows)
