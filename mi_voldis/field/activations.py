"""Activations that map raw grid values to density and colour, accurate over the whole float range
on every backend.

Dr.Jit has no ``log1p``/``expm1``, and on CUDA its ``exp`` and ``log`` are the hardware approximations
(``ex2.approx`` of x log2(e), ``lg2.approx``): ``exp(x)`` then loses |x| 2^-24 relative precision to the
rounded argument, and ``lg2.approx`` has an absolute, not relative, error near 1, so that any
``log(1 + u)`` of a tiny u (Goldberg's ``log(u) x / (u - 1)`` included) is wrong in its first digit
(softplus(-16) came out 62% too large on an H100). The forms below use ``exp`` only on arguments in
[-ln2 / 2, ln2 / 2] and no ``log`` at all, so LLVM and CUDA both keep a relative error below 1e-6 for
softplus and sigmoid of any argument and 1 - exp(-x) of any x >= 0 (densities of 1e-8 do not round
to 0 and are not off by percents).

The formulas are written once over an ``ops`` namespace (:data:`DRJIT` in production) so that the tests
evaluate the very same code with NumPy and an emulated approximate ``exp`` (tests/cuda_emulation.py).
"""
from types import SimpleNamespace

import drjit as dr
import numpy as np

LOG2E = 1.4426950408889634
# ln 2 = LN2_HI + LN2_LO, LN2_HI with 9 significant bits so that n LN2_HI is exact for |n| <= 2^15
# (Cody and Waite's argument reduction)
LN2_HI = 0.693359375
LN2_LO = -2.12194440054690583e-4


def _pow2(n):
    """2^n, exactly, for integer-valued Dr.Jit floats n in [-126, 127]: the float whose exponent field
    holds n + 127 and whose mantissa is 0."""
    t = type(n)
    biased = dr.uint32_array_t(t)(dr.int32_array_t(t)(n) + 127)
    return dr.reinterpret_array(t, biased << 23)


DRJIT = SimpleNamespace(exp=dr.exp, pow2=_pow2, round=dr.round, clip=dr.clip, select=dr.select,
                        minimum=dr.minimum)
"""The operations the formulas use, on Dr.Jit arrays of the active variant (``exp``: the backend's own)."""


def exp(x, ops=DRJIT):
    """e^x with the relative precision of the backend's exp near 0, for every x: e^x = 2^n e^r with
    n = round(x / ln2) clipped to the normal exponents [-126, 127] and r = x - n ln2 (in
    [-ln2 / 2, ln2 / 2] unless n was clipped; then e^r under- or overflows as e^x does)."""
    n = ops.clip(ops.round(x * LOG2E), -126.0, 127.0)
    r = (x - n * LN2_HI) - n * LN2_LO
    return ops.exp(r) * ops.pow2(n)


def log1p_unit(u):
    """log(1 + u) for u in [0, 1] without a logarithm: 2 atanh(s) with s = u / (2 + u) in [0, 1/3], its
    series to s^13 (truncation < s^15 / 15, relative < 3^-14 / 15 = 1.4e-8)."""
    s = u / (2.0 + u)
    z = s * s
    series = 1 / 3 + z * (1 / 5 + z * (1 / 7 + z * (1 / 9 + z * (1 / 11 + z * (1 / 13)))))
    return 2.0 * (s + s * z * series)


def _minus_abs(x, ops):
    """-|x| as a select, whose derivative at 0 is that of the branch x >= 0 (-1); the derivative of abs
    there is 0, which would leave raw values of exactly 0 (grey colours) without a gradient."""
    return ops.select(x >= 0.0, -x, x)


def softplus(x, ops=DRJIT):
    """Density activation sigma = softplus(x) = log(1 + e^x): positive, smooth, never dead.

    Evaluated as max(x, 0) + log1p(e^-|x|) so that it neither overflows for large x nor loses
    precision for very negative x (softplus(-13.8) = 1e-6 and softplus(-30) = 9.4e-14 to float
    precision)."""
    return ops.select(x >= 0.0, x, 0.0) + log1p_unit(exp(_minus_abs(x, ops), ops))


def sigmoid(x, ops=DRJIT):
    """Colour activation c = 1 / (1 + e^-x), in (0, 1): with e = e^-|x| <= 1, 1 / (1 + e) for x >= 0 and
    e / (1 + e) below (no overflow, full relative precision as c goes to 0)."""
    e = exp(_minus_abs(x, ops), ops)
    d = 1.0 / (1.0 + e)
    return ops.select(x >= 0.0, d, e * d)


def one_minus_exp(x, ops=DRJIT):
    """1 - exp(-x) for x >= 0 without cancellation for small x: below 0.5, its Taylor series to x^8
    (truncation < x^9 / 9!, relative < 2^-8 / 9! = 1.1e-8); above, where 1 - exp(-x) >= 0.39, the error
    of exp is amplified at most e^-x / (1 - e^-x) < 1.6 times. The series is evaluated at min(x, 0.5):
    x^8 of a large x would overflow, and its infinite derivative times the zero gradient of the branch
    not taken would make NaN."""
    s = ops.minimum(x, 0.5)
    series = s * (1.0 - s * (1 / 2 - s * (1 / 6 - s * (1 / 24 - s * (1 / 120 - s * (
        1 / 720 - s * (1 / 5040 - s * (1 / 40320))))))))
    return ops.select(x < 0.5, series, 1.0 - exp(-x, ops))


def inverse_softplus(sigma):
    """Raw value whose softplus is ``sigma`` (NumPy, float64): log(e^sigma - 1)."""
    sigma = np.asarray(sigma, dtype=np.float64)
    with np.errstate(divide="ignore", over="ignore"):
        return np.where(sigma > 20.0, sigma + np.log1p(-np.exp(-sigma)), np.log(np.expm1(sigma)))


def logit(color):
    """Raw colour whose sigmoid is ``color`` (NumPy); clipped to stay finite at 0 and 1."""
    c = np.clip(np.asarray(color, dtype=np.float64), 1e-6, 1.0 - 1e-6)
    return np.log(c / (1.0 - c))
