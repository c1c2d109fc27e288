"""The guided background's start on the test suite's sphere-on-a-floor scene (tests/test_background.py), filled
isotropically and along the horizontal: raw density of the floor vertices under the sphere (the floor is 4).
    python reports/experiments/2026-11-28/hull_fill_vertical/sphere_floor.py"""
import sys
import tempfile

import numpy as np

sys.path.insert(0, "tests")
from test_background import FLOOR_Y, guided_removal, vertex_positions  # noqa: E402

from mi_voldis.field_state import density_of  # noqa: E402

for vertical in (1.0, 0.0):
    _, _, _, state = guided_removal(__import__("pathlib").Path(tempfile.mkdtemp()), steps_bg=0,
                                    hull_fill_vertical=vertical)
    bg = state.fields["bg"]
    pts, real = vertex_positions(bg)
    under = real & (np.hypot(pts[:, 0], pts[:, 2]) < 0.25) & (np.abs(pts[:, 1] - FLOOR_Y) < 0.5 * 2.0 / 39)
    d = density_of(bg)[under]
    print(f"hull_fill_vertical={vertical}: floor under the sphere, raw density min {d.min():.2f}, "
          f"median {np.median(d):.2f}, max {d.max():.2f} ({under.sum()} vertices)")
