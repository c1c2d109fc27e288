"""What the grid probes share (`cull_free.py`, `fog_views.py`, `../2026-12-02e/cull.py`): checking RUN and OUT,
a run's full-field vertices from its `full_grid.npz`, a copy of the run with some vertices emptied, and its
held-out views scored against the photos. Import after `mi_voldis` (it points Dr.Jit at a working libLLVM)."""
import os
import shutil

import numpy as np
from PIL import Image

import mi_voldis
from mi_voldis.bricks import EMPTY_DENSITY, Layout


def check_paths(script, run, out):
    """Stop in one line unless RUN is a run folder and OUT a new folder outside it."""
    if not os.path.isfile(os.path.join(run, "full_grid.npz")):
        raise SystemExit(f"{script}: {run}: not a run folder (no full_grid.npz)")
    if os.path.lexists(out):
        raise SystemExit(f"{script}: {out} exists; give a new folder")
    if os.path.realpath(out).startswith(os.path.realpath(run) + os.sep):
        raise SystemExit(f"{script}: {out} lies inside the run {run}; give a folder outside it")


def grid_vertices(run):
    """The grid file's arrays, whether each stored vertex lies in the lattice, and its world position
    (where it does not: 0)."""
    z = dict(np.load(os.path.join(run, "full_grid.npz")))
    lay = Layout(tuple(z["vertices"]), int(z["brick"]), z["table"])
    coords, inside = lay.vertex_coords()
    if len(coords) == len(z["data"]) + lay.vertices_per_brick:  # the file leaves out the empty slot
        coords, inside = coords[lay.vertices_per_brick:], inside[lay.vertices_per_brick:]
    lo, hi = z["bbox"]
    return z, inside, np.where(inside[:, None], lo + coords / (np.array(lay.shape) - 1) * (hi - lo), 0.0)


def score(path, ds, out, label):
    """Print the full field's PSNR in each held-out view of ``ds`` and save its 8-bit previews to OUT."""
    rr = mi_voldis.load_run(path)
    line = []
    for v in ds.test:
        full = np.clip(rr.render(view=int(v), layers=("full",), linear=False)["full"][..., :3], 0, 1)
        line.append(f"v{int(v)} {-10 * np.log10(((full - ds.images[int(v)]) ** 2).mean()):.2f}")
        Image.fromarray((full * 255 + 0.5).astype(np.uint8)).save(os.path.join(out, f"{label}_v{int(v):03d}.png"))
    print(f"{label}: " + "  ".join(line), flush=True)


def emptied_copy(run, z, kill, dest):
    """A copy of the run in the new folder ``dest`` (no checkpoints, no previews) whose full field is empty
    at the vertices ``kill`` (Bool per stored vertex)."""
    os.makedirs(dest)
    for f in os.listdir(run):
        if f not in ("full_grid.npz", "checkpoints", "previews"):
            src = os.path.join(run, f)
            (shutil.copytree if os.path.isdir(src) else shutil.copy2)(src, os.path.join(dest, f))
    data = z["data"].copy()
    data[kill, 0] = EMPTY_DENSITY
    np.savez(os.path.join(dest, "full_grid.npz"), **{**z, "data": data})
