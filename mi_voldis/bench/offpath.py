"""Views off the training path: a held-out camera moved lower, closer and wider, rendered from a fitted run.

The training cameras of a capture span a rig (a forward-facing slab, a 360-degree ring); a user's new
path leaves it. Each moved view steps from a held-out camera by a fifth of the scene's median depth in
that view (down, or forward); the sheet shows photo, the held-out view rendered, and the moved views,
so black bands or a missing far background show at a glance.
"""
import copy

import mitsuba as mi
import numpy as np

from ..data import load_dataset
from ..io.images import contact_sheet, display_to_uint8, write_png
from ..render.views import render_camera


def moved_cameras(ds, view, depth, scale=0.5):
    """{name: Camera}: held-out ``view`` as is, lower and closer by a fifth of ``depth`` (the scene's
    distance from it), and lower with a wider field of view, at ``scale`` times its resolution."""
    base = copy.deepcopy(ds.cameras[view])
    base.width, base.height = int(base.width * scale), int(base.height * scale)
    step = 0.2 * depth
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
    tiles = [display_to_uint8(ds.images[view][::2, ::2])]
    small = copy.deepcopy(ds.cameras[view])
    small.width, small.height = small.width // 4, small.height // 4
    _, alpha, z = render_camera(integrator, small, ("full",))["full"]
    depth = float(np.median(z[alpha > 0.5])) if (alpha > 0.5).any() else 1.0
    for camera in moved_cameras(ds, view, depth).values():
        tiles.append(display_to_uint8(render_camera(integrator, camera, ("full",))["full"][0]))
    write_png(out_png, contact_sheet(tiles, columns=len(tiles)))
    return out_png
