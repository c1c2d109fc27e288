"""Layered OpenEXR files: the main image as R, G, B, A and named layers beside it.

Channel names follow the convention Nuke and Blender read (a pass is the name before the last dot):
``R, G, B, A`` (premultiplied) for the main image, ``<layer>.R/G/B/A`` for the others, ``depth.Z`` and
``<layer>_depth.Z`` for depths, each its own pass (:mod:`mi_voldis.compositing`).
"""
import os

import numpy as np
import OpenEXR

from .run_folder import temp_beside


def write_exr(path, channels, header=None):
    """Write ``{name: (H, W) float array}`` as a ZIP-compressed float32 scanline EXR, with the extra
    ``header`` attributes (name -> str, float tuple or 4x4 float32 matrix).

    Written to a temporary file and renamed, so an existing file is never left half-written."""
    if not channels:
        raise ValueError(f"{path}: no channels to write")
    shapes = {np.shape(v) for v in channels.values()}
    if len(shapes) != 1 or len(next(iter(shapes))) != 2:
        raise ValueError(f"{path}: all channels must be 2D arrays of one size, got {sorted(shapes)}")
    data = {name: np.ascontiguousarray(value, dtype=np.float32) for name, value in channels.items()}
    header = {**(header or {}), "compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    tmp = temp_beside(path, ".exr")
    with OpenEXR.File(header, data) as f:
        f.write(tmp)
    os.replace(tmp, path)


def read_exr_header(path):
    """The header attributes of an EXR file."""
    try:
        with OpenEXR.File(str(path)) as f:
            return dict(f.header())
    except Exception as e:
        raise ValueError(f"{path}: cannot read EXR file ({e})") from None


def read_exr(path):
    """``{name: (H, W) float32 array}`` of every channel of an EXR file."""
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such EXR file")
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            return {name: np.array(ch.pixels, dtype=np.float32) for name, ch in f.channels().items()}
    except Exception as e:  # OpenEXR raises bare exceptions for corrupt files
        raise ValueError(f"{path}: cannot read EXR file ({e})") from None
