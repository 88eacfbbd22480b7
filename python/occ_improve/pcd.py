"""Organized PCD files (PCL's format: ascii, binary and binary_compressed) into numpy, without PCL.

PCL's own reader is C++ and the module does not link PCL (the core stays Eigen + std), so the header is
parsed here and the data decoded with numpy; binary_compressed data is LZF, decoded by the module's
`_lzf_decompress` (C++, no GIL). Every header value is checked as pcl_tools/src/pcd_header.cpp checks it
for the tools (PCL's reader trusts the header), and the data's size against the file's: a malformed
file is a FormatError naming the file and the field, never a crash or a huge allocation.
"""
from __future__ import annotations

import dataclasses
import os
from typing import List, Optional, Tuple, Union

import numpy as np

from ._core import FormatError, IoError, _lzf_decompress

PathLike = Union[str, "os.PathLike[str]"]

_MAX_HEADER_BYTES = 1 << 16
_MAX_FIELDS, _MAX_COUNT = 1024, 1 << 16
_MAX_COMPRESSION_RATIO = 128  # LZF encodes at most 264 bytes in a 3-byte back reference
_KINDS = {"I": "i", "U": "u", "F": "f"}


@dataclasses.dataclass
class PcdCloud:
    """A PCD file's points as numpy arrays, in the file's (height, width) order.

    points: (H, W, 3) float32 x, y, z (NaN where PCL writes no point); rgb: (H, W, 3) uint8 from a packed
    rgb / rgba field, else None; fields: every field of the file as an (H, W) structured array (a field
    of COUNT n has shape (n,) per point); viewpoint: the VIEWPOINT line (tx ty tz qw qx qy qz).
    """

    points: np.ndarray
    rgb: Optional[np.ndarray]
    fields: np.ndarray
    viewpoint: Tuple[float, ...]
    data: str  # ascii, binary or binary_compressed

    @property
    def height(self) -> int:
        return self.points.shape[0]

    @property
    def width(self) -> int:
        return self.points.shape[1]


@dataclasses.dataclass
class _Header:
    names: List[str]
    sizes: List[int]
    types: List[str]
    counts: List[int]
    width: int = 0
    height: int = 0
    points: int = 0
    viewpoint: Tuple[float, ...] = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    data: str = ""
    data_offset: int = 0

    def dtype(self) -> np.dtype:
        """The packed record of one point, little-endian as PCL writes it; pad fields ('_') get unique names."""
        names = [f"_pad{i}" if n == "_" else n for i, n in enumerate(self.names)]
        return np.dtype([(n, f"<{_KINDS[t]}{s}", (c,) if c > 1 else ()) for n, s, t, c in
                         zip(names, self.sizes, self.types, self.counts)])


def _fail(path: str, problem: str) -> None:
    raise FormatError(f"PCD file '{path}': {problem}")


def _number(path: str, key: str, text: str, low: int, high: int) -> int:
    if not text.isdigit() or not low <= int(text) <= high:
        _fail(path, f"{key} {text} is invalid: must be a whole number in [{low}, {high}]")
    return int(text)


def _per_field(path: str, header: _Header, key: str, values: List[str]) -> None:
    if len(values) != len(header.names):
        _fail(path, f"{key} has {len(values)} values for {len(header.names)} fields")
    for i, (name, value) in enumerate(zip(header.names, values)):
        what = f"{key} of field '{name}'"
        if key == "SIZE":
            if value not in ("1", "2", "4", "8"):
                _fail(path, f"{what} {value} is not 1, 2, 4 or 8")
            header.sizes[i] = int(value)
        elif key == "TYPE":
            if value not in _KINDS:
                _fail(path, f"{what} '{value}' is not I, U or F")
            header.types[i] = value
        else:
            header.counts[i] = _number(path, what, value, 1, _MAX_COUNT)


def _parse_header(path: str, head: bytes) -> _Header:
    header = _Header([], [], [], [])
    offset, seen = 0, set()
    while True:
        end = head.find(b"\n", offset)
        if end < 0:
            _fail(path, "no DATA line in the header" if len(head) < _MAX_HEADER_BYTES else
                  f"no DATA line in the first {_MAX_HEADER_BYTES} bytes")
        line = head[offset:end].decode("ascii", "replace").strip()
        offset = end + 1
        if not line or line.startswith("#"):
            continue
        key, *values = line.split()
        seen.add(key)
        if key in ("FIELDS", "COLUMNS"):
            if not 1 <= len(values) <= _MAX_FIELDS:
                _fail(path, f"FIELDS must name 1 to {_MAX_FIELDS} fields")
            header.names, header.sizes = values, [4] * len(values)
            header.types, header.counts = ["F"] * len(values), [1] * len(values)
        elif key in ("SIZE", "TYPE", "COUNT"):
            _per_field(path, header, key, values)
        elif key in ("WIDTH", "HEIGHT", "POINTS"):
            value = _number(path, key, values[0] if len(values) == 1 else " ".join(values), 0, 2**32 - 1)
            setattr(header, key.lower(), value)
        elif key == "VIEWPOINT":
            try:
                header.viewpoint = tuple(float(v) for v in values)
            except ValueError:
                header.viewpoint = ()
            if len(header.viewpoint) != 7:
                _fail(path, f"VIEWPOINT must hold 7 numbers, got '{' '.join(values)}'")
        elif key == "DATA":
            if values not in (["ascii"], ["binary"], ["binary_compressed"]):
                _fail(path, f"DATA '{' '.join(values)}' is not ascii, binary or binary_compressed")
            header.data, header.data_offset = values[0], offset
            break
        elif key != "VERSION":
            _fail(path, f"unknown header line '{line[:40]}'")
    for required in ("FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT"):
        if required not in seen and not (required == "FIELDS" and "COLUMNS" in seen):
            _fail(path, f"the header has no {required} line")
    # A float of 1 or 2 bytes is no PCL type (the tools refuse it, pcd_header.cpp; numpy would read 2 as
    # float16, garbage), and a field named twice would leave one of them unreadable (numpy's record type
    # refuses the name without saying which file).
    for name, size, kind in zip(header.names, header.sizes, header.types):
        if kind == "F" and size not in (4, 8):
            _fail(path, f"TYPE F of field '{name}' needs SIZE 4 or 8, got {size}")
    named = [n for n in header.names if n != "_"]
    for name in named:
        if named.count(name) > 1:
            _fail(path, f"field '{name}' occurs more than once")
    if "POINTS" not in seen:
        header.points = header.width * header.height
    if header.width * header.height != header.points:
        _fail(path, f"WIDTH x HEIGHT ({header.width} x {header.height}) is not POINTS ({header.points})")
    return header


def _ascii_records(path: str, header: _Header, body: bytes) -> np.ndarray:
    tokens = body.split()
    columns = sum(header.counts)
    if len(tokens) != header.points * columns:
        _fail(path, f"ascii data holds {len(tokens)} values, the header declares {header.points} points x "
                    f"{columns} values")
    table = np.array(tokens, dtype=bytes).reshape(header.points, columns)
    records = np.zeros(header.points, dtype=header.dtype())
    column = 0
    for name, size, kind, count in zip(records.dtype.names, header.sizes, header.types, header.counts):
        text = table[:, column:column + count].reshape(header.points, *((count,) if count > 1 else ()))
        column += count
        try:
            if kind == "F" and size == 4 and "rgb" in name and text.size and np.char.isdigit(text).all():
                # PCL writes a packed colour stored in a float as its integer bits.
                records[name] = text.astype(np.uint64).astype(np.uint32).view(np.float32)
            elif kind == "F":
                records[name] = text.astype(np.float64)
            else:
                records[name] = text.astype(np.int64 if kind == "I" else np.uint64)
        except (ValueError, OverflowError):
            _fail(path, f"ascii values of field '{name}' are not {'numbers' if kind == 'F' else 'whole numbers'}")
    return records


def _compressed_records(path: str, header: _Header, raw: bytes) -> np.ndarray:
    record = header.dtype()
    start = header.data_offset
    if len(raw) < start + 8:
        _fail(path, "binary_compressed data has no size fields")
    compressed, uncompressed = (int(v) for v in np.frombuffer(raw, "<u4", 2, start))
    expected = header.points * record.itemsize
    if uncompressed != expected:
        _fail(path, f"binary_compressed data declares {uncompressed} bytes, the header {expected}")
    if start + 8 + compressed > len(raw):
        _fail(path, f"binary_compressed data declares {compressed} compressed bytes, the file holds "
                    f"{len(raw) - start - 8}")
    if uncompressed > compressed * _MAX_COMPRESSION_RATIO:
        _fail(path, f"binary_compressed data declares {uncompressed} bytes from {compressed}: not LZF data")
    try:
        plain = _lzf_decompress(raw[start + 8:start + 8 + compressed], uncompressed) if expected else b""
    except FormatError as e:  # the decompressor knows the bytes, not the file
        _fail(path, str(e))
    # Field after field (all points' x, then all y, ...): PCL's layout for better compression.
    records = np.empty(header.points, dtype=record)
    offset = 0
    for name in record.names:
        field = record.fields[name][0]
        records[name] = np.frombuffer(plain, field, header.points, offset)
        offset += field.itemsize * header.points
    return records


def _binary_records(path: str, header: _Header, raw: bytes) -> np.ndarray:
    record = header.dtype()
    available = len(raw) - header.data_offset
    if available < header.points * record.itemsize:
        _fail(path, f"binary data holds {available} bytes, the header declares {header.points} points x "
                    f"{record.itemsize} bytes")
    return np.frombuffer(raw, record, header.points, header.data_offset).copy()


def _colours(records: np.ndarray) -> Optional[np.ndarray]:
    """(.., 3) uint8 from PCL's packed colour (0x00RRGGBB in a float's or a uint32's 4 bytes)."""
    name = next((n for n in ("rgb", "rgba") if n in records.dtype.names), None)
    if name is None or records.dtype.fields[name][0].itemsize != 4 or records.dtype.fields[name][0].shape:
        return None
    packed = records[name].view(np.uint32) if records[name].dtype.kind == "f" else records[name].astype(np.uint32)
    return np.stack([(packed >> 16) & 255, (packed >> 8) & 255, packed & 255], axis=-1).astype(np.uint8)


def read_pcd(path: PathLike) -> PcdCloud:
    """Reads a PCD file as PCL writes it (ascii, binary, binary_compressed) into (H, W, ...) arrays.

    Raises IoError when the file cannot be read, FormatError naming the file and the problem when it is
    not a valid PCD file or has no float x, y, z fields.
    """
    name = os.fspath(path)
    try:
        with open(name, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise IoError(f"cannot read PCD file '{name}': {e.strerror or e}") from e
    header = _parse_header(name, raw[:_MAX_HEADER_BYTES])
    if header.data == "ascii":
        records = _ascii_records(name, header, raw[header.data_offset:])
    elif header.data == "binary":
        records = _binary_records(name, header, raw)
    else:
        records = _compressed_records(name, header, raw)
    for axis in "xyz":
        if axis not in header.names or header.types[header.names.index(axis)] != "F" or \
                header.counts[header.names.index(axis)] != 1:
            _fail(name, f"no float field '{axis}' of one value (fields: {' '.join(header.names)})")
    records = records.reshape(header.height, header.width)
    points = np.stack([records[a].astype(np.float32) for a in "xyz"], axis=-1)
    return PcdCloud(points=points, rgb=_colours(records), fields=records, viewpoint=header.viewpoint,
                    data=header.data)
