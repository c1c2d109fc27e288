"""Mitsuba ``.vol`` grid files: read and write through ``mi.VolumeGrid``, plus the header's box.

Format (Mitsuba's binary volume format, version 3): bytes 'VOL', version 3, int32 encoding (1 =
float32), int32 X, Y, Z, channels, six float32 for the bounding box (min xyz, max xyz), then the
data in (Z, Y, X, C) order. Any channel count is allowed by the format; Mitsuba's built-in
``gridvolume`` only accepts 1, 3 or 6, so spherical-harmonic colour grids (12 or 27 channels) are
read by the ``radiance_field`` plugin only; a grey degree-1 grid (6 channels) loads into ``gridvolume`` too,
which reads it as two RGB triples, not as view dependence.
"""
import os

import mitsuba as mi
import numpy as np

from .run_folder import temp_beside

HEADER_BYTES = 48
BBOX_OFFSET = 24


def read_header(path):
    """(X, Y, Z, channels, bbox_min, bbox_max) of a .vol file; raises ``ValueError`` naming the file."""
    try:
        with open(path, "rb") as f:
            header = f.read(HEADER_BYTES)
    except OSError as e:
        raise ValueError(f"{path}: cannot read volume file ({e.strerror})") from None
    if len(header) < HEADER_BYTES or header[:3] != b"VOL" or header[3] != 3:
        raise ValueError(f"{path}: not a Mitsuba .vol file (version 3 header expected)")
    encoding, x, y, z, channels = np.frombuffer(header, dtype="<i4", count=5, offset=4)
    if encoding != 1:
        raise ValueError(f"{path}: .vol encoding {encoding} is not supported (float32 = 1 expected)")
    bbox = np.frombuffer(header, dtype="<f4", count=6, offset=BBOX_OFFSET).astype(np.float64)
    expected = HEADER_BYTES + 4 * int(x) * int(y) * int(z) * int(channels)
    size = os.path.getsize(path)
    if size != expected:
        raise ValueError(f"{path}: truncated or corrupt .vol file ({size} bytes, header says {expected})")
    return int(x), int(y), int(z), int(channels), bbox[:3], bbox[3:]


def read_vol(path):
    """Grid values of a .vol file as a float32 array of shape (Z, Y, X, C)."""
    read_header(path)
    return grid_values(mi.VolumeGrid(str(path)))


def grid_values(volume_grid):
    """(Z, Y, X, C) float32 array of a ``mi.VolumeGrid`` (NumPy drops the channel axis when C = 1)."""
    x, y, z = volume_grid.size()
    return np.array(volume_grid, dtype=np.float32).reshape(z, y, x, volume_grid.channel_count())


def write_vol(path, values, bbox_min=(0, 0, 0), bbox_max=(1, 1, 1)):
    """Write a (Z, Y, X, C) array to ``path`` with the given bounding box in the header.

    Written to a temporary file and renamed, so an existing file is never left half-written."""
    values = np.ascontiguousarray(values, dtype=np.float32)
    if values.ndim != 4:
        raise ValueError(f"{path}: volume data must have shape (Z, Y, X, C), got {values.shape}")
    path = str(path)
    tmp = temp_beside(path)
    mi.VolumeGrid(values).write(tmp)
    bbox = np.concatenate([np.asarray(bbox_min, np.float32), np.asarray(bbox_max, np.float32)])
    with open(tmp, "r+b") as f:
        f.seek(BBOX_OFFSET)
        f.write(bbox.astype("<f4").tobytes())
    os.replace(tmp, path)
