"""NumPy arrays into Dr.Jit arrays at a fixed memory alignment.

Dr.Jit wraps a NumPy buffer without copying it and compiles the buffer's alignment into every kernel
that reads it (``align 64`` or ``align 1`` in the LLVM IR). NumPy's buffers fall on either from one
call to the next, so kernels fed fresh NumPy arrays every step would be compiled again and again
(reports/notes.md). :func:`from_numpy` copies the values into a 64-byte-aligned buffer first, so that a
kernel compiles once.
"""
import drjit as dr
import numpy as np

ALIGN = 64  # bytes: an AVX-512 register, and what Dr.Jit's own allocations use


def aligned(values, dtype):
    """A C-contiguous copy of ``values`` as ``dtype`` whose first element sits on an ALIGN boundary."""
    values = np.asarray(values, dtype)
    item = values.itemsize
    buf = np.empty(values.size + ALIGN // item, dtype)
    start = (-buf.ctypes.data % ALIGN) // item
    out = buf[start:start + values.size].reshape(values.shape)
    out[...] = values
    return out


def from_numpy(cls, values):
    """``cls`` (a Dr.Jit array type: ``mi.Float``, ``mi.UInt32``, ``mi.Point3f``, ...) holding
    ``values``: shape (n,) for a scalar type, (n, k) for a type of k components."""
    dtype = {dr.VarType.UInt32: np.uint32, dr.VarType.Float64: np.float64, dr.VarType.Bool: np.bool_}.get(
        dr.type_v(cls), np.float32)
    if dr.depth_v(cls) == 1:
        return cls(aligned(values, dtype))
    values = np.asarray(values)
    return cls(*[aligned(values[:, k], dtype) for k in range(values.shape[1])])
