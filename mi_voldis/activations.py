"""Activations that map raw grid values to density and colour, accurate over the whole float range.

Dr.Jit has no ``log1p``/``expm1``; the forms below keep full relative precision where the naive
``log(1 + x)`` and ``1 - exp(-x)`` cancel (densities of 1e-6 must not round to 0).
"""
import drjit as dr
import numpy as np


def log1p(x):
    """log(1 + x) for x > -1, accurate near 0 (Goldberg's trick: log(u) * x / (u - 1), u = 1 + x)."""
    u = 1.0 + x
    return dr.select(u == 1.0, x, dr.log(u) * x / (u - 1.0))


def softplus(x):
    """Density activation sigma = softplus(x) = log(1 + e^x): positive, smooth, never dead.

    Evaluated as max(x, 0) + log1p(e^-|x|) so that it neither overflows for large x nor loses
    precision for very negative x (softplus(-13.8) = 1e-6 to float precision)."""
    return dr.maximum(x, 0.0) + log1p(dr.exp(-dr.abs(x)))


def sigmoid(x):
    """Colour activation c = 1 / (1 + e^-x), in (0, 1)."""
    return dr.rcp(1.0 + dr.exp(-x))


def one_minus_exp(x):
    """1 - exp(-x) for x >= 0 without cancellation for small x: below 0.1, its Taylor series to x^6
    (truncation error < x^7 / 5040), so the relative error stays below 1e-6 for every x."""
    series = x * (1.0 - x * (1 / 2 - x * (1 / 6 - x * (1 / 24 - x * (1 / 120 - x * (1 / 720))))))
    return dr.select(x < 0.1, series, 1.0 - dr.exp(-x))


def inverse_softplus(sigma):
    """Raw value whose softplus is ``sigma`` (NumPy, float64): log(e^sigma - 1)."""
    sigma = np.asarray(sigma, dtype=np.float64)
    with np.errstate(divide="ignore", over="ignore"):
        return np.where(sigma > 20.0, sigma + np.log1p(-np.exp(-sigma)), np.log(np.expm1(sigma)))


def logit(color):
    """Raw colour whose sigmoid is ``color`` (NumPy); clipped to stay finite at 0 and 1."""
    c = np.clip(np.asarray(color, dtype=np.float64), 1e-6, 1.0 - 1e-6)
    return np.log(c / (1.0 - c))


