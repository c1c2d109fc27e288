"""NumPy emulation of the float32 arithmetic a CUDA variant compiles the activations to, for testing
:mod:`mi_voldis.field.activations` without a GPU.

On CUDA, Dr.Jit evaluates ``dr.exp(x)`` as ``ex2.approx.ftz.f32(x * log2(e))`` and ``dr.log(x)`` as
``lg2.approx.ftz.f32(x) * ln(2)``. The PTX ISA bounds ``ex2.approx``'s error relative to its result and
``lg2.approx``'s absolutely; both flush subnormal results to zero. Here the argument is rounded to
float32 as on the GPU and the exact result is moved by the whole error bound in the direction ``bias``
(+1 or -1), the worst case a formula must survive. Every other operation is NumPy's IEEE float32
arithmetic, as Dr.Jit's ``+ - * /`` are on both backends.
"""
from types import SimpleNamespace

import numpy as np

EX2_ERROR = 2.0 ** -22  # relative
LG2_ERROR = 2.0 ** -22  # absolute, in log2 units
SMALLEST_NORMAL = np.finfo(np.float32).tiny


def f32(x):
    return np.asarray(x, np.float32)


def _flush(y):
    return np.where(np.abs(y) < SMALLEST_NORMAL, np.float32(0.0), y).astype(np.float32)


def approx_ops(bias):
    """An ``ops`` namespace for :mod:`mi_voldis.field.activations` whose exp (and log, for comparisons with
    formulations that use it) err by ``bias`` times the hardware's bound."""
    def exp(x):
        a = f32(f32(x) * np.float32(np.log2(np.e)))
        with np.errstate(over="ignore"):
            return _flush(f32(np.exp2(a.astype(np.float64)) * (1.0 + bias * EX2_ERROR)))

    def log(x):
        with np.errstate(divide="ignore", invalid="ignore"):
            lg2 = f32(np.log2(f32(x).astype(np.float64)) + bias * LG2_ERROR)
        return f32(lg2 * np.float32(np.log(2.0)))

    def pow2(n):
        return f32(np.ldexp(np.float32(1.0), np.asarray(n).astype(np.int32)))

    return SimpleNamespace(exp=exp, log=log, pow2=pow2, round=np.rint, clip=np.clip, select=np.where,
                           abs=np.abs, maximum=np.maximum, minimum=np.minimum)
