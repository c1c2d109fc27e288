"""An exponential moving average of a fit's iterates (Polyak-Ruppert averaging with forgetting).

Adam's last iterate carries the noise of its last steps: each voxel is moved by the few random rays that
crossed it in a step, at a rate that has decayed only to ``lr_final_ratio``. From a first step s on,

    a_s = p_s,        a_k = beta a_{k-1} + (1 - beta) p_k,        beta = 1 - 1 / tau,

weights the iterate j steps back by (1 - beta) beta^j: a window of about tau steps, over which that noise
averages out (its variance falls by about 1 / (2 tau) for uncorrelated steps), while a drift slower than
the window is followed, about tau steps behind. Iterates a few steps apart differ by little, so the
average takes every k-th one, k = :func:`stride` (about ITERATES_PER_WINDOW a window), with beta = 1 - k / tau:
the same window at 1 / k of the passes over the fields (each pass reads and writes every packed value).
"""
import math

import drjit as dr

ITERATES_PER_WINDOW = 32


def stride(steps):
    """Every how many steps an average over a window of ``steps`` steps takes an iterate (at least 1)."""
    return max(1, math.floor(steps / ITERATES_PER_WINDOW))


def window_decay(steps, every=1):
    """The decay beta of an average over a window of ``steps`` steps taking every ``every``-th iterate
    (1 - every / steps; 0, the last iterate alone, for a window of ``every`` steps or less)."""
    return max(0.0, 1.0 - every / steps) if steps > 0 else 0.0


def moving_average(average, value, beta):
    """The average after one more iterate ``value``: beta ``average`` + (1 - beta) ``value``, evaluated;
    a copy of ``value`` where ``average`` is None (the first iterate averaged)."""
    value = dr.detach(value)
    out = dr.copy(value) if average is None else dr.fma(average, beta, value * (1.0 - beta))
    dr.eval(out)
    return out
