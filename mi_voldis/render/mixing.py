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

RULES = ("paper", "c2", "c3", "c4", "density")
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


def needed_sources(sources, rule, layers):
    """Lookup keys the given layers need."""
    keys = set()
    if "full" in layers:
        keys.add(sources.full)
    if "bg" in layers:
        keys.add(sources.bg)
    if "fg" in layers or "composite" in layers:
        keys |= {sources.bg, sources.full_q, sources.bg_q} if "composite" in layers else \
            {sources.full_q, sources.bg_q}
        if sources.fg_color:
            keys.add(sources.fg_color)
    if "res" in layers and sources.residual:
        keys.add(sources.residual)
    return keys


def _add(terms, chain, layer, g, k):
    key = (chain, layer)
    if key in terms:
        g0, k0 = terms[key]
        g, k = g0 + g, k0 + k
    terms[key] = (g, k)


def compose(rule, sources, layers, v):
    """Chains and terms of one sample.

    ``v``: lookup key -> (sigma, color, inside). Returns ``(sigmas, terms)``: chain -> density,
    and (chain, layer) -> (colour coefficient, alpha coefficient)."""
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
        (sf, cf, _), (sb, cb, _) = v[s.full_q], v[s.bg_q]
        c_fg = cf - cb  # paper Eq. 3
        if s.fg_color:
            c_fg = dr.select(v[s.fg_color][2], v[s.fg_color][1], c_fg)
        sig[s.full_q], sig[s.bg_q] = sf, sb
        if "fg" in layers:
            _add(terms, s.full_q, "fg", c_fg, one)
            _add(terms, s.bg_q, "fg", -c_fg, -one)
        if "composite" in layers:
            sig[s.bg] = v[s.bg][0]
            _compose_rule(rule, s, v, sig, terms, c_fg)
    if "res" in layers and s.residual:
        sig[s.residual] = v[s.residual][0]
        _add(terms, s.residual, "res", v[s.residual][1], one)
    return sig, terms


def _compose_rule(rule, s, v, sig, terms, c_fg):
    one = mi.Float(1.0)
    c_bg = v[s.bg][1]
    if rule == "density":
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
        _add(terms, MIX, "composite", color, one)
        return
    if rule == "c4":
        c_mix = c_bg + c_fg
        _add(terms, s.bg, "composite", c_mix, one)
        _add(terms, s.full_q, "composite", c_mix, one)
        _add(terms, s.bg_q, "composite", -c_mix, -one)
        return
    _add(terms, s.bg, "composite", c_bg, one)
    if rule == "paper":
        _add(terms, s.full_q, "composite", c_fg, one)
        _add(terms, s.bg_q, "composite", -c_fg, -one)
    elif rule == "c2":
        c_full = v[s.full_q][1]
        _add(terms, s.full_q, "composite", c_full, one)
        _add(terms, s.bg_q, "composite", -c_full, -one)
    elif rule == "c3":
        _add(terms, s.full_q, "composite", c_fg, one)
    else:
        raise ValueError(f"unknown composition rule '{rule}' (expected one of {', '.join(RULES)})")
