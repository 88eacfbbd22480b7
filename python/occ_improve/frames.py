"""Reading real frames without PCL: 16-bit depth PNGs (7-Scenes, TUM, SUN3D), intrinsics files, a 3 x 3 K
and Open3D's PinholeCameraIntrinsic (organized PCD files: occ_improve.pcd).

PNG decoding uses Pillow (installed with matplotlib), imported only when a PNG is read, so the core
module needs numpy alone.
"""
from __future__ import annotations

import os
from typing import Union

import numpy as np

import math

from ._core import InvalidInput, InvalidParameter, IoError, PinholeIntrinsics, _intrinsics_from_matrix

PathLike = Union[str, "os.PathLike[str]"]


def read_depth_png(path: PathLike, scale: float = 0.001) -> np.ndarray:
    """A 16-bit depth PNG as an H x W float32 array in metres (value * scale; 0 stays 0 = no return).

    scale: 0.001 for millimetres (Kinect/OpenNI, 7-Scenes, SUN3D), 1/5000 for TUM; finite and > 0.
    value * scale is computed in double and rounded to float32 once, as Mapper.insert_depth(values,
    scale=scale) does: both give the same map.
    Raises IoError when the file cannot be read, InvalidInput when it is not a 16-bit grey image,
    InvalidParameter for a scale that is not finite and > 0.
    """
    _require_scale(scale)
    try:
        from PIL import Image
    except ImportError as e:  # the message says what to install, not just that an import failed
        raise ImportError("read_depth_png needs Pillow (Debian: python3-pil; pip: pillow)") from e
    try:
        with Image.open(os.fspath(path)) as image:
            mode = image.mode
            values = np.asarray(image)
    except OSError as e:
        raise IoError(f"cannot read depth image '{os.fspath(path)}': {e}") from e
    except Image.DecompressionBombError as e:  # a header claiming gigapixels: Pillow refuses to decode it
        raise InvalidInput(f"depth image '{os.fspath(path)}': {e}") from e
    # Pillow reports 16-bit grey PNGs as "I;16" or widens them to 32-bit "I" (as it reads 32-bit signed
    # TIFFs: their values must then fit 16 bits, negative ones included).
    if (values.ndim != 2 or mode not in ("I", "I;16", "I;16B") or values.max(initial=0) > 65535
            or values.min(initial=0) < 0):
        raise InvalidInput(f"'{os.fspath(path)}' is not a 16-bit grey depth image (mode {mode}, shape {values.shape})")
    # float32(mm) * float32(scale) rounds twice (the scale, then the product): 1 ulp off on about half the
    # pixels from insert_depth's double product.
    return (values.astype(np.float64) * float(scale)).astype(np.float32)


def _require_scale(scale) -> None:
    """As Mapper.insert_depth checks its scale (and words the error): a negative scale gave negative
    depths, NaN a frame without a return, both silently."""
    if not (math.isfinite(scale) and scale > 0):
        raise InvalidParameter(f"scale = {float(scale):g} is invalid: must be finite and > 0")


def read_intrinsics(path: PathLike, width: int = 640, height: int = 480) -> PinholeIntrinsics:
    """Intrinsics from a text file: "fx fy cx cy [width height]" or a 3 x 3 matrix (7-Scenes, 3DMatch)."""
    try:
        with open(os.fspath(path)) as f:
            numbers = [float(v) for v in f.read().split()]
    except OSError as e:
        raise IoError(f"cannot read intrinsics '{os.fspath(path)}': {e}") from e
    except ValueError as e:
        raise InvalidInput(f"intrinsics '{os.fspath(path)}' hold something other than numbers") from e
    if len(numbers) == 9:
        try:
            return intrinsics_from_matrix(np.reshape(numbers, (3, 3)), width, height)
        except InvalidInput as e:
            raise InvalidInput(f"intrinsics '{os.fspath(path)}': {e}") from e
    if len(numbers) in (4, 6):
        fx, fy, cx, cy = numbers[:4]
        if len(numbers) == 6:
            width, height = _image_size(path, numbers[4], numbers[5])
    else:
        raise InvalidInput(f"intrinsics '{os.fspath(path)}': expected 4, 6 or 9 numbers, got {len(numbers)}")
    k = PinholeIntrinsics(fx=fx, fy=fy, cx=cx, cy=cy, width=width, height=height)
    k.validate()
    return k


def _image_size(what, width, height):
    """Whole numbers of pixels: 320.7 was silently 320."""
    if any(not float(v).is_integer() for v in (width, height)):
        raise InvalidInput(f"intrinsics '{os.fspath(what)}': width and height must be whole numbers, got {width} x {height}")
    return int(width), int(height)


def intrinsics_from_matrix(k, width: int, height: int) -> PinholeIntrinsics:
    """PinholeIntrinsics from a 3 x 3 camera matrix K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] and the image size.

    The image size is not in K, so it is asked for. Raises InvalidInput for another shape, a skew or a
    last row other than (0, 0, 1) (the library's pinhole has neither), InvalidParameter for bad values.
    """
    if np.iscomplexobj(k):  # float64 would drop the imaginary parts with a warning only
        raise TypeError("K must be real, got a complex array")
    k = np.asarray(k, dtype=np.float64)
    if k.shape != (3, 3):
        raise InvalidInput(f"K must be a 3 x 3 matrix, got shape {k.shape}")
    width, height = _image_size("K", width, height)
    return _intrinsics_from_matrix(k.ravel().tolist(), width, height)  # the tools' rule (camera_matrix.hpp)


def intrinsics_from_open3d(camera) -> PinholeIntrinsics:
    """PinholeIntrinsics from an Open3D ``PinholeCameraIntrinsic``, or any object with its attributes
    ``intrinsic_matrix`` (3 x 3), ``width`` and ``height`` (duck-typed: Open3D itself is not imported).
    """
    missing = [a for a in ("intrinsic_matrix", "width", "height") if not hasattr(camera, a)]
    if missing:
        raise TypeError(f"{type(camera).__name__} is not a pinhole camera like Open3D's PinholeCameraIntrinsic: "
                        f"no {', '.join(missing)}")
    return intrinsics_from_matrix(camera.intrinsic_matrix, camera.width, camera.height)


def depth_to_points(depth: np.ndarray, intrinsics: PinholeIntrinsics) -> np.ndarray:
    """Back-projects an H x W depth image (metres) to an H x W x 3 float32 cloud; no return -> NaN.

    The same formula as the library's insertion, for plotting or for handing points to other tools.
    """
    depth = np.asarray(depth, dtype=np.float32)
    if depth.shape != (intrinsics.height, intrinsics.width):
        raise InvalidInput(f"depth has shape {depth.shape}, the intrinsics say ({intrinsics.height}, {intrinsics.width})")
    v, u = np.mgrid[0 : intrinsics.height, 0 : intrinsics.width]
    valid = np.isfinite(depth) & (depth > 0)
    z = np.where(valid, depth, np.nan).astype(np.float32)
    x = ((u - intrinsics.cx) * z / intrinsics.fx).astype(np.float32)
    y = ((v - intrinsics.cy) * z / intrinsics.fy).astype(np.float32)
    return np.stack([x, y, z], axis=-1)
