"""family16 fitted with a thin contracted shell (contract_shell 0.25): is its wall density that no training
view frames? Empties every full-field vertex fewer than K training views frame (its world position in front
of the camera and inside its image) and scores the held-out views, for each K given.

usage: python cull_unframed.py RUN OUT K...   # OUT: a new folder; writes OUT/K<k>/ run copies
"""
import os
import sys

import numpy as np

import mi_voldis  # noqa: I001  (first: it points Dr.Jit at a working libLLVM)
from mi_voldis.cameras import DevicePoints

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "2026-12-02g"))
from grid_probe import check_paths, emptied_copy, grid_vertices, score  # noqa: E402

args = sys.argv[1:]
if len(args) < 3 or not all(k.isdigit() for k in args[2:]):
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
run, out, ks = args[0], args[1], [int(k) for k in args[2:]]
check_paths("cull_unframed.py", run, out)
rr = mi_voldis.load_run(run)
ds = rr.dataset
space = rr.integrator().plan(("full",)).space
z, inside, scene_pos = grid_vertices(run)
world = space.to_world_np(scene_pos[inside])
framed = np.zeros(len(world), int)
at = DevicePoints(world)
for v in ds.train:
    _, ok = at.pixel_of(ds.cameras[v])
    framed += np.array(ok, dtype=int)
counts = np.full(len(inside), 10 ** 6)
counts[inside] = framed
occupied = z["data"][:, 0] > -5  # raw density above the empty value's neighbourhood
print(f"{inside.sum()} vertices in the lattice; framed by no training view: {np.mean(framed == 0):.3f}; "
      f"among those with raw density > -5: {np.mean(counts[occupied & inside] == 0):.3f}", flush=True)
os.makedirs(out)
score(run, ds, out, "fit")
for k in ks:
    dest = os.path.join(out, f"K{k}")
    emptied_copy(run, z, counts < k, dest)
    score(dest, ds, out, f"K{k}")
