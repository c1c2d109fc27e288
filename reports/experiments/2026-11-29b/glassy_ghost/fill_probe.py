"""#46: what the background's start puts where the object stood, by height.

    python reports/experiments/2026-11-29b/glassy_ghost/fill_probe.py RUN   # RUN fitted with --keep-checkpoints

The hull's harmonic fill (mi_voldis.fit.background.harmonic_fill, with the region and weights start_harmonic
gives it) after 300 Jacobi iterations (the code's) and 3000, as opacity per voxel of the refilled vertices that
are not the object's; then, by height (the scene's y, the fill's vertical on the family's scenes), the refilled
vertices after 300 iterations beside the fixed values the fill reads along the horizontal: the kept hull
vertices some view sees unmasked, and the vertices outside the hull.
"""
import json
import os
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_voldis  # noqa: F401  (sets the variant)
from mi_voldis.bench.strategies import refit_config
from mi_voldis.data import load_dataset
from mi_voldis.field_state import neighbour_vertices, vertex_positions
from mi_voldis.fit.background import background_regions, fill_weights, harmonic_fill, voxel_of
from mi_voldis.fit.fields import FitInputs
from mi_voldis.fit.state import FitState
from mi_voldis.optim.adam import Adam

run = sys.argv[1]
cfg = refit_config(run, "guided")
with open(os.path.join(run, "config.json")) as f:
    rec = json.load(f)["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, 0.9, 0.99))
state.fields.pop("bg", None)
inputs = FitInputs.of(ds, cfg, "/tmp/none.npz", progress=False)
full = state.fields["full"]
nb = neighbour_vertices(full)
hull, points, obj, refill = background_regions(inputs, state, nb)
weights = fill_weights(inputs, full, points)
print("fill weights (-x, +x, -y, +y, -z, +z)", weights, "grid", full.shape)
region = dr.select(refill, hull, 0.0)
scale, vox = full.density_scale, voxel_of(full)


def alpha(raw):
    """Opacity of one voxel's length at raw density ``raw``."""
    return 1.0 - np.exp(-np.log1p(np.exp(raw)) * scale * vox)


def raw_density(values):
    return np.array(dr.gather(mi.Float, values, dr.arange(mi.UInt32, full.vertices) * full.width))


reg, o, h = np.array(region) > 0, np.array(obj), np.array(hull) > 0
refilled = reg & ~o
filled = {}
for iterations in (300, 3000):
    filled[iterations] = raw_density(harmonic_fill(full.data, full.width, region, nb, iterations=iterations,
                                                   weights=weights))
    a = alpha(filled[iterations][refilled])
    print(f"{iterations} iterations: {refilled.sum()} refilled vertices outside the object's, opacity per voxel "
          f"10/50/90%: {np.round(np.percentile(a, [10, 50, 90]), 4)}")
raw0 = raw_density(full.data)
rim = np.zeros(len(raw0), bool)  # fixed vertices next to the region along the horizontal
for k in (0, 1, 4, 5):
    rim[np.array(nb[k])[reg]] = True
rim &= ~reg
y = vertex_positions(full)[0][:, 1]


def mean_alpha(raw, sel):
    return f"{alpha(raw[sel]).mean():.4f}" if sel.any() else "-"


for lo in np.arange(-0.05, 1.0, 0.1):
    band = (y >= lo) & (y < lo + 0.1)
    if not (refilled & band).any():
        continue
    print(f"y {lo:+.2f}..{lo + 0.1:+.2f}: refilled {(refilled & band).sum():6d}, "
          f"opacity {mean_alpha(filled[300], refilled & band)}"
          f" | rim in the hull (kept) {(rim & h & band).sum():5d}, {mean_alpha(raw0, rim & h & band)}"
          f" | rim outside the hull {(rim & ~h & band).sum():5d}, {mean_alpha(raw0, rim & ~h & band)}")
