"""The plan's memory bound of fitted captures at other bytes a pixel / a vertex, from their metrics.json.

    python reports/experiments/2026-12-06i/plan_bounds.py NAME=METRICS.json... (NAME a capture in ../shared/data)
"""
import json
import os
import sys

import mi_voldis.fit.schedule as schedule
from mi_voldis.data import load_dataset
from mi_voldis.fit.config import FitConfig

DATA = os.environ.get("MI_VOLDIS_CAPTURES", "../shared/data")
cfg = FitConfig.from_sources(None, ["max_memory_gib=4"])
for arg in sys.argv[1:]:
    name, path = arg.split("=", 1)
    metrics = json.load(open(path))
    plan = metrics["schedule"]["plan"]
    ds = load_dataset(os.path.join(DATA, name))
    pixels = len(ds.train) * ds.size[0] * ds.size[1]
    rows = []
    for per_pixel, per_vertex in ((30, 272), (22, 272), (22, 250)):
        schedule.BYTES_PER_PIXEL, schedule.BYTES_PER_VERTEX = per_pixel, per_vertex
        bound = schedule.memory_resolution(cfg, plan["surface_cells"], plan["surface_resolution"], 64,
                                           metrics["sh_degree"], pixels)
        rows.append(f"{per_pixel} B/px, {per_vertex} B/vertex: {bound}")
    print(f"{name} ({pixels} pixels; plan's bounds {plan['resolution_bounds']}): " + "; ".join(rows))
