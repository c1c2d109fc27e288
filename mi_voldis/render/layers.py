"""Layer outputs: from the march's raw sums to RGBA + depth, and the adjoint of that step.

A layer's raw sums over samples are (sum w c, sum w, sum w t). Its outputs are the premultiplied
colour RGB = sum w c, alpha A = sum w, and depth Z = sum w t / sum w, the expected distance at which
the ray ends given that it ends in this layer (0 where |A| < ALPHA_EPS: the layer is empty there).
Foreground weights w_fg = w_full - w_bg may be negative, so a foreground alpha can be too.
"""
import drjit as dr
import mitsuba as mi

from .march import term_name

ALPHA_EPS = 1e-4
EXR_LAYERS = ("full", "bg", "fg")  # layers written beside the main image; "res" when present


def raw_sums(plan, acc):
    """layer -> [R, G, B, A, D] summed over the chains contributing to it."""
    sums = {}
    for chain, layer in plan.terms:
        a = acc[term_name(chain, layer)]
        sums[layer] = a if layer not in sums else [s + v for s, v in zip(sums[layer], a)]
    for layer in plan.layers:  # a layer with no terms (e.g. fg of nothing) is zero
        sums.setdefault(layer, [mi.Float(0.0)] * 5)
    return sums


def finalize(sums):
    """layer -> (rgb Color3f, alpha Float, depth Float)."""
    out = {}
    for layer, (r, g, b, a, d) in sums.items():
        valid = dr.abs(a) > ALPHA_EPS
        out[layer] = (mi.Color3f(r, g, b), a, dr.select(valid, d / dr.select(valid, a, 1.0), 0.0))
    return out


def finalize_adjoint(sums, grads):
    """Adjoint of :func:`finalize`: layer -> (dRGB, dA, dD) on the raw sums, given output adjoints."""
    out = {}
    for layer, (g_rgb, g_alpha, g_depth) in grads.items():
        _, _, _, a, d = sums[layer]
        valid = dr.abs(a) > ALPHA_EPS
        inv_a = dr.select(valid, dr.rcp(dr.select(valid, a, 1.0)), 0.0)
        out[layer] = (mi.Color3f(g_rgb), g_alpha - g_depth * d * inv_a * inv_a, g_depth * inv_a)
    return out
