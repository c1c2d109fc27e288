"""Affine transforms as float64 NumPy 4x4 matrices, and their application to Dr.Jit points.

Matrices are kept on the host in double precision and baked into kernels as literal constants, so a
transform costs no memory traffic per sample and inverting it loses no precision.
"""
import drjit as dr
import mitsuba as mi
import numpy as np


def to_matrix(transform):
    """4x4 float64 matrix of a Mitsuba transform, a 4x4 array-like, or ``None`` (identity)."""
    if transform is None:
        return np.eye(4)
    if hasattr(transform, "matrix"):
        transform = transform.matrix
    m = np.array(transform, dtype=np.float64)
    if m.shape != (4, 4):
        raise ValueError(f"a transform must be a 4x4 matrix, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ValueError("a transform must have finite entries")
    return m


def is_identity(m, tol=0.0):
    return bool(np.all(np.abs(np.asarray(m) - np.eye(4)) <= tol))


def apply_point(m, p):
    """m * (p, 1) for an affine ``m`` (NumPy 4x4) and ``p`` a ``mi.Point3f``/``mi.Vector3f``."""
    m = np.asarray(m, dtype=np.float64).tolist()  # Python floats: literals in the kernel
    return mi.Point3f(*[dr.fma(r[0], p.x, dr.fma(r[1], p.y, dr.fma(r[2], p.z, r[3]))) for r in m[:3]])


def apply_vector(m, v):
    """Linear part of ``m`` applied to the vector ``v``."""
    m = np.asarray(m, dtype=np.float64).tolist()
    return mi.Vector3f(*[dr.fma(r[0], v.x, dr.fma(r[1], v.y, r[2] * v.z)) for r in m[:3]])


def to_scalar_transform(m):
    """``mi.ScalarTransform4f`` of a NumPy matrix (for XML writing and Mitsuba APIs)."""
    return mi.ScalarTransform4f(np.asarray(m, dtype=np.float32))


def compose(scale=1.0, rotate=None, translate=(0.0, 0.0, 0.0), pivot=(0.0, 0.0, 0.0)):
    """Matrix of ``p -> R S (p - pivot) + pivot + translate``.

    ``scale``: a number or three numbers; ``rotate``: ``(axis, degrees)`` with axis 'x', 'y', 'z' or a
    3-vector. Scaling and rotation are about ``pivot`` (e.g. an object's centre)."""
    s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,))
    if np.any(s == 0) or not np.all(np.isfinite(s)):
        raise ValueError(f"scale must be finite and non-zero, got {scale}")
    r = np.eye(3)
    if rotate is not None:
        axis, degrees = rotate
        axis = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}.get(axis, axis)
        a = np.asarray(axis, dtype=np.float64)
        if a.shape != (3,) or np.linalg.norm(a) == 0:
            raise ValueError(f"rotation axis must be x, y, z or a non-zero 3-vector, got {axis}")
        a = a / np.linalg.norm(a)
        th = np.radians(degrees)
        k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        r = np.eye(3) + np.sin(th) * k + (1 - np.cos(th)) * (k @ k)
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(s)
    pivot = np.asarray(pivot, dtype=np.float64)
    m[:3, 3] = pivot - m[:3, :3] @ pivot + np.asarray(translate, dtype=np.float64)
    return m


def quaternion_to_rotation(q):
    """3x3 rotation of a quaternion (w, x, y, z), normalised first."""
    w, x, y, z = np.asarray(q, np.float64) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def rotation_to_quaternion(r):
    """Unit quaternion (w, x, y, z) of a 3x3 rotation (Shepperd's method: the largest of w, x, y, z
    is found first, so that no division is by a small number)."""
    r = np.asarray(r, np.float64)
    trace = np.trace(r)
    i = int(np.argmax([trace, r[0, 0], r[1, 1], r[2, 2]]))
    if i == 0:
        w = np.sqrt(1 + trace) / 2
        q = np.array([w, (r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w), (r[1, 0] - r[0, 1]) / (4 * w)])
    else:
        a = i - 1
        b, c = (a + 1) % 3, (a + 2) % 3
        s = np.sqrt(max(0.0, 1 + r[a, a] - r[b, b] - r[c, c])) * 2
        q = np.zeros(4)
        q[0], q[1 + a] = (r[c, b] - r[b, c]) / s, s / 4
        q[1 + b], q[1 + c] = (r[b, a] + r[a, b]) / s, (r[c, a] + r[a, c]) / s
    return q / np.linalg.norm(q)

