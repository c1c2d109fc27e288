"""The shadow search alone (mi_voldis.fit.shadow.find_shadow) on fitted runs kept with their checkpoints.

    python reports/experiments/2026-11-27/shadow/search.py RUN [RUN ...] [--set KEY=VALUE ...] > out.json

Per RUN: the light its fit recorded (metrics.json bg_prior.shadow) beside the light today's code finds
from the same full field, and for the removal family's scenes the true light (the rectangle emitter or
point light of the dataset's scene/scene.xml) with the angle, seen from the origin, to each.
"""
import json
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))))))

from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.fields import FitInputs  # noqa: E402
from mi_voldis.fit.shadow import find_shadow  # noqa: E402
from mi_voldis.fit.state import FitState  # noqa: E402
from mi_voldis.optim.adam import Adam  # noqa: E402


def true_light(dataset):
    path = os.path.join(dataset, "scene", "scene.xml")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        xml = f.read()
    m = re.search(r'id="light".*?origin="([^"]+)"', xml) or re.search(
        r'type="point".*?name="position" value="([^"]+)"', xml, re.S)
    return [float(v) for v in m.group(1).split(",")] if m else None


def angle(a, b):
    if a is None or b is None:
        return None
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.degrees(np.arccos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1))))


def kept_run(run, sets=()):
    """A fit kept with its checkpoints: its dataset record, the shadow its fit recorded, the fit's
    inputs (dataset and settings, ``sets`` applied) and its final state."""
    cfg = FitConfig.from_sources(os.path.join(run, "config.json"), list(sets))
    with open(os.path.join(run, "config.json")) as f:
        record = json.load(f)["dataset"]
    with open(os.path.join(run, "metrics.json")) as f:
        before = (json.load(f).get("bg_prior") or {}).get("shadow")
    ds = load_dataset(record["path"], record["format"], record["holdout"])
    state = FitState.load(os.path.join(run, "checkpoints", "last.npz"), Adam({}, cfg.adam_beta1, cfg.adam_beta2))
    return record, before, FitInputs.of(ds, cfg, "/nonexistent/state.npz", False), state


def search(run, sets=()):
    record, before, inputs, state = kept_run(run, sets)
    _, now = find_shadow(inputs, state)
    truth = true_light(record["path"])
    return {"run": run, "true": truth, "before": before, "now": now,
            "angle_before": angle(before and before["light"], truth), "angle_now": angle(now and now["light"], truth)}


if __name__ == "__main__":
    args = sys.argv[1:]
    sets = [args[k + 1] for k, a in enumerate(args) if a == "--set"]
    runs = [a for k, a in enumerate(args) if a != "--set" and (k == 0 or args[k - 1] != "--set")]
    print(json.dumps([search(r, sets) for r in runs], indent=1, default=float))
