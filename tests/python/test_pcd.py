"""read_pcd: organized PCD files (ascii, binary, binary_compressed as PCL writes them) into numpy, on
clouds this test writes itself, on the real Kinect clouds of ../shared/data (skipped where absent), and
against the C++ tool, which reads them through PCL."""
import os
import subprocess

import numpy as np
import pytest

import occ_improve as oi
from conftest import assert_same_maps, data_file

FIVE_PEOPLE = "kinect/pcl_test/five_people.pcd"
PERSON = "kinect/pcl_tutorials/person.pcd"


def lzf_compress(data: bytes) -> bytes:
    """A small LZF encoder: literal runs, and a back reference of distance 1 for every run of >= 3 equal
    bytes (PCL's NaN padding compresses this way). Valid LZF for any decoder, liblzf's included."""
    out, literal, i = bytearray(), bytearray(), 0

    def flush():
        for start in range(0, len(literal), 32):
            chunk = literal[start:start + 32]
            out.append(len(chunk) - 1)
            out.extend(chunk)
        literal.clear()

    while i < len(data):
        run = 1
        while i + run < len(data) and data[i + run] == data[i] and run < 265:
            run += 1
        if run >= 4:  # one literal byte, then run - 1 copies of the byte just written
            literal.append(data[i])
            flush()
            length = run - 1 - 2
            if length < 7:
                out.append(length << 5)
            else:
                out.extend([7 << 5, length - 7])
            out.append(0)  # distance 1: offset 0
            i += run
        else:
            literal.append(data[i])
            i += 1
    flush()
    return bytes(out)


PCD_TYPES = {"f": "F", "i": "I", "u": "U"}


def write_pcd(path, records: np.ndarray, data: str, viewpoint="0 0 0 1 0 0 0") -> None:
    """records: an (H, W) structured array; written as PCL writes it (fields in order, little-endian)."""
    height, width = records.shape
    names = records.dtype.names
    fields = [records.dtype.fields[n][0] for n in names]
    bases = [f.base if f.shape else f for f in fields]
    counts = [int(np.prod(f.shape)) if f.shape else 1 for f in fields]
    header = (f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {' '.join(names)}\n"
              f"SIZE {' '.join(str(b.itemsize) for b in bases)}\nTYPE {' '.join(PCD_TYPES[b.kind] for b in bases)}\n"
              f"COUNT {' '.join(map(str, counts))}\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT {viewpoint}\n"
              f"POINTS {width * height}\nDATA {data}\n").encode()
    flat = records.reshape(-1)
    if data == "ascii":
        lines = []
        for point in flat:
            values = []
            for name, base in zip(names, bases):
                for v in np.atleast_1d(point[name]):
                    if "rgb" in name and base.kind == "f":  # PCL writes a packed colour as its integer bits
                        values.append(str(int(np.float32(v).view(np.uint32))))
                    elif base.kind == "f":
                        values.append("nan" if np.isnan(v) else "%.9g" % v)
                    else:
                        values.append(str(int(v)))
            lines.append(" ".join(values))
        body = ("\n".join(lines) + "\n").encode()
    elif data == "binary":
        body = flat.astype(flat.dtype.newbyteorder("<")).tobytes()
    else:  # field after field, LZF-compressed, behind the two sizes
        plain = b"".join(np.ascontiguousarray(flat[n]).tobytes() for n in names)
        packed = lzf_compress(plain)
        body = np.array([len(packed), len(plain)], "<u4").tobytes() + packed
    path.write_bytes(header + body)


def generated_records(sample):
    """An organized cloud with holes (NaN), a packed colour, a label and a two-value field."""
    depth, k = sample
    points = oi.depth_to_points(depth, k)[::8, ::8]  # 60 x 80: small enough for the ascii writer
    h, w = points.shape[:2]
    records = np.zeros((h, w), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<f4"),
                                      ("label", "<u4"), ("pair", "<i2", (2,))])
    for i, a in enumerate("xyz"):
        records[a] = points[..., i]
    rng = np.random.default_rng(5)
    colours = rng.integers(0, 256, (h, w, 3), dtype=np.uint32)
    records["rgb"] = ((colours[..., 0] << 16) | (colours[..., 1] << 8) | colours[..., 2]).view(np.float32)
    records["label"] = rng.integers(0, 2**32, (h, w), dtype=np.uint64).astype(np.uint32)
    records["pair"] = rng.integers(-30000, 30000, (h, w, 2))
    return records, points, colours.astype(np.uint8)


@pytest.mark.parametrize("data", ["ascii", "binary", "binary_compressed"])
def test_every_encoding_reads_back_the_written_cloud(tmp_path, sample, data):
    records, points, colours = generated_records(sample)
    assert np.isnan(points[..., 2]).any() and np.isfinite(points[..., 2]).any()
    path = tmp_path / f"{data}.pcd"
    write_pcd(path, records, data, viewpoint="0.5 0 0 1 0 0 0")
    cloud = oi.read_pcd(path)
    assert cloud.data == data and (cloud.height, cloud.width) == records.shape
    assert cloud.points.dtype == np.float32 and cloud.points.shape == records.shape + (3,)
    np.testing.assert_array_equal(cloud.points, points)  # NaN where the sample has no return
    np.testing.assert_array_equal(cloud.rgb, colours)
    np.testing.assert_array_equal(cloud.fields["label"], records["label"])
    np.testing.assert_array_equal(cloud.fields["pair"], records["pair"])
    assert cloud.fields["pair"].shape == records.shape + (2,)
    assert cloud.viewpoint == (0.5, 0, 0, 1, 0, 0, 0)


def test_a_cloud_without_colour_and_with_float64_coordinates(tmp_path, sample):
    records, points, _ = generated_records(sample)
    plain = np.zeros(records.shape, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")])
    for i, a in enumerate("xyz"):
        plain[a] = points[..., i]
    write_pcd(tmp_path / "d.pcd", plain, "binary")
    cloud = oi.read_pcd(tmp_path / "d.pcd")
    assert cloud.rgb is None and cloud.points.dtype == np.float32
    np.testing.assert_array_equal(cloud.points, points)


def test_lzf_decoder_on_a_known_stream():
    # literal "ab", then a back reference of length 2 + 2 at distance 2 ("abab"), then literal "c".
    stream = bytes([1]) + b"ab" + bytes([2 << 5, 1]) + bytes([0]) + b"c"
    assert oi._core._lzf_decompress(stream, 7) == b"abababc"
    data = bytes(range(50)) * 3 + b"\x00" * 300 + b"xyz"
    assert oi._core._lzf_decompress(lzf_compress(data), len(data)) == data
    with pytest.raises(oi.FormatError, match="fewer bytes"):
        oi._core._lzf_decompress(stream, 8)
    with pytest.raises(oi.FormatError, match="more bytes"):
        oi._core._lzf_decompress(stream, 6)
    with pytest.raises(oi.FormatError, match="before the start"):
        oi._core._lzf_decompress(bytes([2 << 5, 5]), 4)
    with pytest.raises(oi.FormatError, match="past the end"):
        oi._core._lzf_decompress(bytes([5]) + b"ab", 6)


def test_malformed_files_name_the_file_and_the_problem(tmp_path, sample):
    records, _, _ = generated_records(sample)
    good = tmp_path / "good.pcd"
    write_pcd(good, records, "binary_compressed")
    raw = good.read_bytes()

    def variant(name, content):
        path = tmp_path / name
        path.write_bytes(content)
        return path

    with pytest.raises(oi.FormatError, match="wrong_points.pcd.*POINTS"):
        oi.read_pcd(variant("wrong_points.pcd", raw.replace(b"POINTS 4800", b"POINTS 4801")))
    with pytest.raises(oi.FormatError, match="SIZE of field 'x' 3"):
        oi.read_pcd(variant("size.pcd", raw.replace(b"SIZE 4", b"SIZE 3")))
    with pytest.raises(oi.FormatError, match="compressed bytes"):
        oi.read_pcd(variant("cut.pcd", raw[:-100]))
    data_at = raw.index(b"DATA binary_compressed\n") + len(b"DATA binary_compressed\n")
    wrong_size = raw[:data_at + 4] + np.array([123], "<u4").tobytes() + raw[data_at + 8:]
    with pytest.raises(oi.FormatError, match="declares 123 bytes"):
        oi.read_pcd(variant("declared.pcd", wrong_size))
    # An LZF stream that opens with a back reference (control byte >= 32): the decoder's error, with the file named.
    corrupt = raw[:data_at + 8] + b"\xff\xff\xff" + raw[data_at + 11:]
    with pytest.raises(oi.FormatError, match="corrupt_body.pcd.*LZF data corrupt"):
        oi.read_pcd(variant("corrupt_body.pcd", corrupt))
    write_pcd(tmp_path / "bin.pcd", records, "binary")
    with pytest.raises(oi.FormatError, match="binary data holds"):
        oi.read_pcd(variant("short.pcd", (tmp_path / "bin.pcd").read_bytes()[:-1]))
    no_z = np.zeros((2, 2), dtype=[("x", "<f4"), ("y", "<f4"), ("depth", "<f4")])
    write_pcd(tmp_path / "no_z.pcd", no_z, "ascii")
    with pytest.raises(oi.FormatError, match="no float field 'z'"):
        oi.read_pcd(tmp_path / "no_z.pcd")
    with pytest.raises(oi.FormatError, match="no DATA line"):
        oi.read_pcd(variant("header_only.pcd", b"VERSION 0.7\nFIELDS x y z\n"))
    with pytest.raises(oi.IoError, match="missing.pcd"):
        oi.read_pcd(tmp_path / "missing.pcd")
    # The tools' checks too: a 2-byte float was read as float16 (garbage points), a 1-byte one and a field
    # named twice raised numpy's errors without the file's name.
    header_at = raw.index(b"SIZE 4")
    for name, size, expected in (("half.pcd", b"SIZE 2", "TYPE F of field 'x' needs SIZE 4 or 8, got 2"),
                                 ("byte.pcd", b"SIZE 1", "TYPE F of field 'x' needs SIZE 4 or 8, got 1")):
        with pytest.raises(oi.FormatError, match=f"{name}.*{expected}"):
            oi.read_pcd(variant(name, raw[:header_at] + size + raw[header_at + 6:]))
    with pytest.raises(oi.FormatError, match="twice.pcd.*field 'x' occurs more than once"):
        oi.read_pcd(variant("twice.pcd", raw.replace(b"FIELDS x y z", b"FIELDS x y x", 1)))


def test_real_kinect_cloud_as_the_data_readme_describes_it():
    cloud = oi.read_pcd(data_file(FIVE_PEOPLE))
    assert cloud.data == "binary_compressed" and cloud.points.shape == (480, 640, 3)
    z = cloud.points[..., 2]
    valid = np.isfinite(z)
    assert valid.mean() == pytest.approx(0.778, abs=0.001)  # "valid 77.8%; z 1.76-9.76 m"
    assert z[valid].min() == pytest.approx(1.76, abs=0.01) and z[valid].max() == pytest.approx(9.76, abs=0.01)
    assert cloud.rgb.shape == (480, 640, 3) and cloud.rgb[valid].std() > 10  # a real colour image
    fit = oi.fit_intrinsics_checked(cloud.points)  # "fx=fy=525, cx=319.5, cy=239.5"
    k = fit.intrinsics
    assert (k.fx, k.fy, k.cx, k.cy) == pytest.approx((525, 525, 319.5, 239.5), abs=1e-3)


def test_real_cloud_re_encoded_reads_back_the_same(tmp_path):
    cloud = oi.read_pcd(data_file(PERSON))
    for data in ("binary", "binary_compressed"):
        write_pcd(tmp_path / f"{data}.pcd", cloud.fields, data)
        again = oi.read_pcd(tmp_path / f"{data}.pcd")
        np.testing.assert_array_equal(again.points, cloud.points)


def test_python_maps_of_a_pcd_equal_the_cpp_tools_maps(tmp_path):
    """The same PCD through occ_improve_map (C++, PCL's reader) and through read_pcd: bit for bit."""
    tool = os.environ.get("OCC_IMPROVE_MAP_TOOL")
    if not tool or not os.access(tool, os.X_OK):
        pytest.skip("occ_improve_map not built (OCC_IMPROVE_MAP_TOOL unset): needs the PCL tools")
    pcd = data_file(PERSON)
    saved = tmp_path / "cpp.occmap"
    subprocess.run([tool, "-preset", "kinect_v1_paper", str(pcd), "-save", str(saved), "-o", str(tmp_path / "out")],
                   check=True, capture_output=True)
    python = oi.Mapper(oi.kinect_v1_paper())
    points = oi.read_pcd(pcd).points
    report = python.insert(points).insertion
    assert report.points_received == 640 * 480
    assert report.skipped_invalid == np.count_nonzero(np.isnan(points[..., 2]))
    assert report.skipped_invalid == pytest.approx(0.21 * 640 * 480, rel=0.01)  # "valid 79.0%"
    assert_same_maps(oi.load_map(saved), python)
