"""The shadow search on a finished run without checkpoints (its scene.xml's full field).

    python reports/experiments/2026-11-27/shadow/from_run.py RUN > out.json

Renders the full field's median depth of every masked training view of RUN's dataset and runs today's
mi_voldis.fit.shadow.shadow_of_depths on them, with RUN's settings: the light found, whether it is kept,
and the share of the masked views' pixels its effect masks take (0 where none is kept), beside the light
RUN's fit recorded.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))))))

from mi_voldis import load_run  # noqa: E402
from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.shadow import shadow_of_depths  # noqa: E402
from mi_voldis.render.surface import median_depth  # noqa: E402


def main(path):
    run = load_run(path)
    ds = run.dataset
    cfg = FitConfig.from_sources(os.path.join(path, "config.json"))
    with open(os.path.join(path, "metrics.json")) as f:
        before = (json.load(f).get("bg_prior") or {}).get("shadow")
    integrator = run.integrator()
    depth = {}
    for v in ds.masked_train:
        d, hit = median_depth(integrator, ds.cameras[v])
        depth[v] = np.where(hit, d, np.nan)
    shadow, now = shadow_of_depths(ds, cfg, depth)
    share = float(shadow[list(ds.masked_train)].mean()) if shadow is not None else 0.0
    return {"run": path, "before": before, "now": now, "effect_share": share}


if __name__ == "__main__":
    print(json.dumps([main(p) for p in sys.argv[1:]], indent=1, default=float))
