# ad hoc: where the default background's weight on the held-out masked pixels lives (by vertex class)
import json, os, sys, time
import numpy as np
import drjit as dr, mitsuba as mi
from mi_voldis.bench.strategies import refit_config
run, out = sys.argv[1], sys.argv[2]
sets = sys.argv[3:]
from mi_voldis.data import load_dataset
from mi_voldis.fit.fields import fit_integrator
from mi_voldis.fit.state import FitState
from mi_voldis.fit.train import fit
from mi_voldis.optim.adam import Adam
cfg = refit_config(run, "guided", sets)
rec = json.load(open(os.path.join(run, "config.json")))["dataset"]
ds = load_dataset(rec["path"], rec["format"], rec["holdout"])
os.makedirs(out, exist_ok=True)
adam = Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup)
state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), adam)
state.fields.pop("bg", None)
state.hull_points = state.prior = state.prior_keys = state.occupancy = None
state.adam.reset()
ck = os.path.join(out, "state.npz"); state.save(ck, "bg", 0)
inputs, state = fit(ds, ck, cfg, resume=True, progress=False)
from mi_voldis.fit.background import background_regions, voxel_of
from mi_voldis.field_state import vertex_positions
from mi_voldis.render import march
from mi_voldis.cameras import pixel_rays
from mi_voldis.device import from_numpy
from mi_voldis.metrics import dilate
hull, points, obj, refill = background_regions(inputs, state)
bg, full = state.fields["bg"], state.fields["full"]
assert bg.vertices == full.vertices
integrator = fit_integrator(inputs, state)
plan = integrator.plan(("bg",))
chain = plan.sources.bg
contrib = dr.zeros(mi.Float, bg.vertices)
m = bg.to_world
origin = mi.Point3f(*(float(x) for x in m[:3, 3]))
scale = mi.Vector3f(*(float(x) for x in (np.array(bg.shape) - 1) / np.diag(m)[:3]))
top = [int(n) - 1 for n in bg.shape]
dil = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))
total = 0
with dr.suspend_grad():
    for v in ds.test:
        py, px = np.nonzero(ds.masks[v])
        if not len(px): continue
        o, d = pixel_rays(ds.cameras[v], px + 0.5, py + 0.5)
        n = len(o); total += n
        def mark(p, w, active, depth):
            c = [mi.UInt32(dr.clip(mi.Int32(dr.round(q)), 0, t)) for q, t in zip((p - origin) * scale, top)]
            dr.scatter_add(contrib, w[chain], bg.layout.address(c[0], c[1], c[2], active), active)
        rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d))
        march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=mark)
c = np.array(contrib) / total
h, ob, rf = np.array(hull) > 0, np.array(obj), np.array(refill)
pos, real = vertex_positions(bg)
print("total weight per masked pixel", c.sum())
for name, sel in [("hull&obj", h & ob), ("hull&refill&~obj", h & rf & ~ob), ("hull&kept(seen)", h & ~rf), ("outside hull", ~h)]:
    print(f"{name:20s} {c[sel].sum():.3f}")
np.savez(out + "/contrib.npz", c=c, hull=h, obj=ob, refill=rf, pos=inputs.space.to_world_np(pos))
