"""sh_degree 'auto' (mi_voldis.fit.sh_degree): the trial fits choose degree 1 for a capture whose colour
changes with the view, and degree 0 for the same capture without that change."""
import json
import os

import imageio.v3 as iio
import mitsuba as mi
import numpy as np
import pytest
from helpers import field_dict
from test_data import write_transforms

from mi_voldis.cameras import Camera, look_at
from mi_voldis.field.spec import box_transform
from mi_voldis.fit.config import FitConfig
from mi_voldis.fit.run import run_fit

VIEWS, WIDTH, HEIGHT = 24, 32, 24


def glossy_capture(root, gloss):
    """An orbit of VIEWS views round a textured ball of our own field, whose grey degree-1 coefficients
    are ``gloss`` (3,): the ball brightens toward one side of the orbit and darkens toward the other."""
    n = 16
    x, y, z = np.meshgrid(*(np.linspace(-1, 1, n),) * 3, indexing="ij")
    r = np.sqrt(x * x + y * y + z * z)
    density = np.where(r < 0.6, 6.0, -8.0)[..., None]
    base = np.stack([x, y - 0.5, 0.5 * z], -1)  # smooth: the coarse stage holds it
    colour = np.concatenate([base, np.broadcast_to(np.asarray(gloss, float), base.shape)], -1)
    field = field_dict(density, colour, box_transform([-1, -1, -1], [1, 1, 1]))
    cams, names = [], []
    os.makedirs(os.path.join(root, "images"), exist_ok=True)
    for k in range(VIEWS):
        a = 2 * np.pi * k / VIEWS
        cam = Camera(look_at([3.0 * np.sin(a), 0.8 + 0.4 * np.sin(3 * a), 3.0 * np.cos(a)], [0.0, 0.0, 0.0]), 40.0,
                     WIDTH, HEIGHT)
        scene = mi.load_dict({"type": "scene", "sensor": cam.sensor_dict(),
                              "integrator": {"type": "voldis", "samples": 16, "full": field, "bg": field}})
        image = np.clip(np.array(mi.render(scene, seed=k))[..., :3], 0, 1)
        names.append(f"view_{k:02d}.png")
        iio.imwrite(os.path.join(root, "images", names[-1]), np.round(image * 255).astype(np.uint8))
        cams.append(cam)
    write_transforms(root, cams, names, forward_facing=False)
    return root


SETS = ["steps_full=300", "lr_warmup=2", "batch_rays=1024", "resolution_schedule=[[0,16],[200,20]]",
        "sh_degree=\"auto\"", "sh_trial_steps=80", "sh_gain_db=0.0", "eval_every=1000", "occupancy_at_step=20",
        "preview_views=0", "steps_bg=2", "sh_color=\"grey\""]


@pytest.mark.parametrize("gloss, degree", [((1.5, 1.5, 1.5), 1), ((0.0, 0.0, 0.0), 0)])
def test_the_trial_fits_give_degree_one_to_colour_that_changes_with_the_view(tmp_path, gloss, degree):
    """With the bar at 0 dB (degree 1 wherever it helps the withheld views at all): degree 1 for the glossy
    ball, degree 0 for the matte one, where the harmonics can only fit the trial views' noise."""
    root = glossy_capture(str(tmp_path / "data"), gloss)
    out = str(tmp_path / "run")
    run_fit(root, out, FitConfig.from_sources(None, SETS), progress=False)
    m = json.load(open(os.path.join(out, "metrics.json")))
    choice = m["sh_choice"]
    gain = choice["val_psnr_degree1"] - choice["val_psnr_degree0"]
    assert (choice["degree"], m["sh_degree"]) == (degree, degree) and (gain > 0) == bool(degree)
    assert m["sh_color"] == ("grey" if degree else "rgb")  # the layout the fields hold
    train = [k for k in range(VIEWS) if k % 8]  # every 8th view is held out
    assert choice["trial_steps"] == 80 and choice["val_views"] == train[::4]
