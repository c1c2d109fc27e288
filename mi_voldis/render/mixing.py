"""Per-sample mixing of the full and background fields into layers (paper Eqs. 3 and 5).

Every layer is a sum over samples of *weights times colours*, and every weight belongs to one
transmittance *chain* (one field evaluated along the ray, or the density mixture). A layer is thus
described per sample by *terms*: for each (chain, layer) a colour coefficient g and an alpha
coefficient k, contributing w_chain * (g, k, k t) to the layer's (premultiplied RGB, alpha, depth
numerator). The integrator's quadrature and its adjoint only ever see these terms, so every rule
below is differentiated exactly by the same code.

Sources, at the shared sample points p (foreground ones at q = T_fg^-1 p, background at T_bg^-1 p):
``full`` F(p), ``bg`` B(T_bg^-1 p), ``full_q`` F(q), ``bg_q`` B(q); optionally a foreground colour field
(camouflage) and a residual field (non-negative inpainting).

Layers, with w_fg = w_full(q) - w_bg(q) and c_fg = c_full(q) - c_bg(q) (paper Eq. 3):
    full:  sum w_F c_F          bg:  sum w'_bg c'_bg          fg:  sum w'_fg c'_fg
    composite (paper Eq. 5 and its ablations):
        paper:    sum w'_bg c'_bg + w'_fg c'_fg
        c2:       sum w'_bg c'_bg + w'_fg c'_full
        c3:       sum w'_bg c'_bg + w'_full c'_fg
        c4:       sum (w'_bg + w'_fg)(c'_bg + c'_fg)
        density:  sigma = sigma'_bg + sigma'_fg, sigma c = sigma'_bg c'_bg + sigma'_fg c'_fg with
                  sigma_fg c_fg = sigma_full c_full - sigma_bg c_bg; then the usual quadrature.
    res:   sum w_R c_R (added to the main image: light added only).
With no edit, c4 and density reproduce the full render; the paper's rule does not in general.
"""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi

LAYERS = ("composite", "full", "bg", "fg")
MIX = "mix"  # chain of the density rule


@dataclass(frozen=True)
class Sources:
    """Lookup keys of each role; equal keys mean the same evaluation (e.g. no transform)."""
    full: str
    bg: str
    full_q: str
    bg_q: str
    fg_color: str | None = None
    residual: str | None = None


def _add(terms, chain, layer, g, k):
    key = (chain, layer)
    if key in terms:
        g0, k0 = terms[key]
        g, k = g0 + g, k0 + k
    terms[key] = (g, k)


# ------------------------------------------------------------------ the foreground (paper Eq. 3)
def foreground_color(s, v):
    """c_fg = c_full(q) - c_bg(q) (paper Eq. 3); inside a foreground colour field's box, its colour."""
    c_fg = v[s.full_q][1] - v[s.bg_q][1]
    if s.fg_color:
        c_fg = dr.select(v[s.fg_color][2], v[s.fg_color][1], c_fg)
    return c_fg


def add_foreground(terms, s, layer, color):
    """Add w_fg * ``color`` to ``layer``, with w_fg = w_full(q) - w_bg(q) (paper Eq. 3): the colour
    on the full field's chain, its negative on the background's."""
    one = mi.Float(1.0)
    _add(terms, s.full_q, layer, color, one)
    _add(terms, s.bg_q, layer, -color, -one)


# ------------------------------------------------------- composition rules (paper Eq. 5, ablations)
def paper_rule(s, v, sig, terms, c_fg):
    """sum w'_bg c'_bg + w'_fg c'_fg (paper Eq. 5)."""
    _add(terms, s.bg, "composite", v[s.bg][1], mi.Float(1.0))
    add_foreground(terms, s, "composite", c_fg)


def c2_rule(s, v, sig, terms, c_fg):
    """sum w'_bg c'_bg + w'_fg c'_full."""
    _add(terms, s.bg, "composite", v[s.bg][1], mi.Float(1.0))
    add_foreground(terms, s, "composite", v[s.full_q][1])


def c3_rule(s, v, sig, terms, c_fg):
    """sum w'_bg c'_bg + w'_full c'_fg."""
    _add(terms, s.bg, "composite", v[s.bg][1], mi.Float(1.0))
    _add(terms, s.full_q, "composite", c_fg, mi.Float(1.0))


def c4_rule(s, v, sig, terms, c_fg):
    """sum (w'_bg + w'_fg)(c'_bg + c'_fg)."""
    c_mix = v[s.bg][1] + c_fg
    _add(terms, s.bg, "composite", c_mix, mi.Float(1.0))
    add_foreground(terms, s, "composite", c_mix)


def density_rule(s, v, sig, terms, c_fg):
    """Physically based density mixing: sigma = sigma'_bg + sigma'_fg and sigma c = sigma'_bg c'_bg +
    sigma'_fg c'_fg with sigma_fg c_fg = sigma_full c_full - sigma_bg c_bg, then the usual quadrature
    on one chain (``MIX``)."""
    sb, cb = v[s.bg][:2]
    sf, cf = v[s.full_q][:2]
    sbq, cbq = v[s.bg_q][:2]
    fg_emission = sf * cf - sbq * cbq  # sigma_fg c_fg of the full-minus-background difference
    if s.fg_color:
        fg_emission = dr.select(v[s.fg_color][2], (sf - sbq) * c_fg, fg_emission)
    if s.bg == s.bg_q:  # same lookup: cancel the background exactly rather than through rounding
        sigma = sf
        emission = sf * cf
        if s.fg_color:
            emission = dr.select(v[s.fg_color][2], sb * cb + fg_emission, emission)
    else:
        sigma = dr.maximum(sb + sf - sbq, 0.0)
        emission = sb * cb + fg_emission
    sig[MIX] = sigma
    color = dr.select(sigma > 0.0, dr.clip(emission / sigma, 0.0, 1.0), 0.0)
    _add(terms, MIX, "composite", color, mi.Float(1.0))


RULES = {"paper": paper_rule, "c2": c2_rule, "c3": c3_rule, "c4": c4_rule, "density": density_rule}


def compose(rule, sources, layers, v):
    """Chains and terms of one sample.

    ``v``: lookup key -> (sigma, color, inside). Returns ``(sigmas, terms)``: chain -> density,
    and (chain, layer) -> (colour coefficient, alpha coefficient)."""
    if rule not in RULES:
        raise ValueError(f"unknown composition rule '{rule}' (expected one of {', '.join(RULES)})")
    s = sources
    sig, terms = {}, {}
    one = mi.Float(1.0)
    if "full" in layers:
        sig[s.full] = v[s.full][0]
        _add(terms, s.full, "full", v[s.full][1], one)
    if "bg" in layers:
        sig[s.bg] = v[s.bg][0]
        _add(terms, s.bg, "bg", v[s.bg][1], one)
    if "fg" in layers or "composite" in layers:
        c_fg = foreground_color(s, v)
        sig[s.full_q], sig[s.bg_q] = v[s.full_q][0], v[s.bg_q][0]
        if "fg" in layers:
            add_foreground(terms, s, "fg", c_fg)
        if "composite" in layers:
            sig[s.bg] = v[s.bg][0]
            RULES[rule](s, v, sig, terms, c_fg)
    if "res" in layers and s.residual:
        sig[s.residual] = v[s.residual][0]
        _add(terms, s.residual, "res", v[s.residual][1], one)
    return sig, terms


class _ReadKeys(dict):
    """Placeholder sample values that remember which lookup keys were read."""

    def __init__(self):
        super().__init__()
        self.read = set()

    def __missing__(self, key):
        self.read.add(key)
        return mi.Float(0.0), mi.Color3f(0.0), mi.Bool(True)


def needed_sources(rule, sources, layers):
    """Lookup keys the given layers need under ``rule``: the keys :func:`compose` reads."""
    values = _ReadKeys()
    compose(rule, sources, layers, values)
    return values.read
