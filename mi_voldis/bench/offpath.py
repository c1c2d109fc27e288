"""Views off the training path: a held-out camera moved lower, closer and wider, rendered from a fitted run.

The training cameras of a capture span a rig (a forward-facing slab, a 360-degree ring); a user's new
path leaves it. Each moved view steps by the rig's spread (the RMS distance of the camera centres from
their mean, at least a tenth of the mean distance to the scene centre) from a held-out camera; the
sheet shows photo, the held-out view rendered, and the moved views, so black bands or a missing far
background show at a glance.
"""
import copy

import mitsuba as mi
import numpy as np

from ..data import load_dataset
from ..io.images import contact_sheet, display_to_uint8, write_png
from ..render.views import render_camera


def moved_cameras(ds, view, scale=0.5):
    """{name: Camera}: held-out ``view`` as is, lower, closer and with a wider field of view, at
    ``scale`` times its resolution."""
    centres = np.array([c.to_world[:3, 3] for c in ds.cameras])
    spread = float(np.sqrt(((centres - centres.mean(0)) ** 2).sum(1).mean()))
    base = copy.deepcopy(ds.cameras[view])
    base.width, base.height = int(base.width * scale), int(base.height * scale)
    depth = float(np.linalg.norm(base.to_world[:3, 3] - centres.mean(0))) + spread
    step = max(spread, 0.1 * depth)
    up, forward = base.to_world[:3, 1], base.to_world[:3, 2]
    views = {"held-out view": base}
    for name, offset in (("lower", -step * up), ("closer", step * forward)):
        c = copy.deepcopy(base)
        c.to_world[:3, 3] = c.to_world[:3, 3] + offset
        views[name] = c
    wide = copy.deepcopy(views["lower"])
    wide.fov_x = min(120.0, 1.5 * wide.fov_x)
    views["lower, 1.5x wider"] = wide
    return views


def offpath_sheet(run, dataset, out_png):
    """Write ``out_png``: photo, then the held-out view and its moved versions rendered from ``run``."""
    ds = load_dataset(dataset)
    integrator = mi.load_file(f"{run}/scene.xml").integrator()
    view = ds.test[0] if len(ds.test) else ds.train[0]
    tiles = []
    photo = ds.images[view][::2, ::2]
    tiles.append(display_to_uint8(photo))
    for camera in moved_cameras(ds, view).values():
        rgb = render_camera(integrator, camera, ("full",))["full"][0]
        tiles.append(display_to_uint8(rgb))
    write_png(out_png, contact_sheet(tiles, columns=len(tiles)))
    return out_png
