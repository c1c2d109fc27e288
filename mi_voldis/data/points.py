"""Sparse 3D points of a capture (COLMAP's points3D, nerfstudio's ``ply_file_path``) and what they give:
the depth bounds of each view and a box around the scene.

Depth bounds follow LLFF's ``imgs2poses``: per view, the 0.1 and 99.9 percentiles of the depths of
the points in front of the camera and inside its frame.
"""
import numpy as np

from .types import DatasetError

PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
             "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
NEAR_FAR_PERCENTILES = (0.1, 99.9)


def read_ply(path):
    """(N, 3) float64 positions of the ``vertex`` element of a PLY file (ascii or binary)."""
    try:
        with open(path, "rb") as f:
            if f.readline().strip() != b"ply":
                raise DatasetError(f"{path}: not a PLY file (no 'ply' magic line)")
            fmt, elements = None, []
            while True:
                line = f.readline()
                if not line:
                    raise DatasetError(f"{path}: the PLY header has no end_header")
                words = line.decode("ascii", "replace").split()
                if not words or words[0] in ("comment", "obj_info"):
                    continue
                if words[0] == "end_header":
                    break
                if words[0] == "format":
                    fmt = words[1]
                elif words[0] == "element":
                    elements.append((words[1], int(words[2]), []))
                elif words[0] == "property" and elements:
                    if words[1] == "list":
                        raise DatasetError(f"{path}: list properties before the vertices are not supported")
                    elements[-1][2].append((words[2], PLY_TYPES.get(words[1])))
            body = f.read()
    except OSError as e:
        raise DatasetError(f"{path}: cannot read the point cloud ({e.strerror})") from None
    if not elements or elements[0][0] != "vertex":
        raise DatasetError(f"{path}: the PLY file's first element is not 'vertex'")
    _, count, props = elements[0]
    names = [n for n, _ in props]
    if not {"x", "y", "z"} <= set(names) or any(t is None for _, t in props):
        raise DatasetError(f"{path}: vertices need x, y, z properties of a known type")
    if fmt == "ascii":
        rows = body.decode("ascii", "replace").split("\n")[:count]
        try:
            table = np.array([[float(v) for v in r.split()[:len(names)]] for r in rows], np.float64)
        except ValueError:
            raise DatasetError(f"{path}: malformed ascii vertex rows") from None
        if table.shape != (count, len(names)):
            raise DatasetError(f"{path}: expected {count} vertices of {len(names)} values")
        cols = {n: table[:, i] for i, n in enumerate(names)}
    elif fmt in ("binary_little_endian", "binary_big_endian"):
        order = "<" if fmt == "binary_little_endian" else ">"
        dtype = np.dtype([(n, order + t) for n, t in props])
        if len(body) < count * dtype.itemsize:
            raise DatasetError(f"{path}: truncated ({len(body)} bytes for {count} vertices)")
        cols = np.frombuffer(body, dtype, count)
    else:
        raise DatasetError(f"{path}: unknown PLY format '{fmt}'")
    pts = np.stack([np.asarray(cols[a], np.float64) for a in "xyz"], axis=1)
    return pts[np.isfinite(pts).all(axis=1)]


def depth_bounds(cameras, points):
    """(N, 2) near and far depth (along each camera's axis) of ``points`` seen by each camera, or
    None for a camera that sees fewer than 10 points (:data:`NEAR_FAR_PERCENTILES`)."""
    out = []
    for cam in cameras:
        m = np.linalg.inv(np.asarray(cam.to_world, np.float64))
        local = points @ m[:3, :3].T + m[:3, 3]
        z = local[:, 2]
        tan_x, tan_y = cam.tan_scale
        inside = (z > 0) & (np.abs(local[:, 0]) <= 0.5 * tan_x * z) & (np.abs(local[:, 1]) <= 0.5 * tan_y * z)
        if inside.sum() < 10:
            out.append(None)
            continue
        out.append(np.percentile(z[inside], NEAR_FAR_PERCENTILES))
    return out


def points_box(points, percentiles=(1, 99)):
    """Axis-aligned box holding all but the outermost points (each coordinate's percentiles)."""
    lo, hi = np.percentile(points, percentiles, axis=0)
    return lo, hi
