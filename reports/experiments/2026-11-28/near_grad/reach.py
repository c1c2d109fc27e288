"""Where near_grad can act on a capture: its r (near_grad = 1: the rig's extent) against the distance where
the fit's rays start sampling (the scene box's near bound). Where r is below it, every sample lies beyond r
and the fit is the default's bit for bit.

    python reports/experiments/2026-11-28/near_grad/reach.py DATASET [DATASET ...]
"""
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.data.scene_box import rig_extent  # noqa: E402
from mi_voldis.data.types import DatasetError  # noqa: E402
from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.fields import FitInputs  # noqa: E402


def main(*paths):
    cfg = FitConfig()
    for path in paths:
        try:
            ds = load_dataset(path)
        except DatasetError as e:
            sys.exit(f"error: {e}")
        inputs = FitInputs.of(ds, cfg, None, progress=False)
        r = rig_extent([ds.cameras[v] for v in ds.train])
        near = float(inputs.box.near)
        print(f"{os.path.basename(path.rstrip('/'))}: space {inputs.space.kind}, r (near_grad 1) {r:.3f}, "
              f"sampling starts at {near:.3f}: {'no sample within r' if r <= near else 'acts'}")


if __name__ == "__main__":
    main(*sys.argv[1:])
