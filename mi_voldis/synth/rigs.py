"""Camera rigs for synthetic datasets: an orbit (360 degrees), a forward-facing grid (LLFF-like) and a
hand-held path (explicit positions, each camera looking at its own target)."""
import numpy as np

from ..cameras import Camera, look_at  # noqa: F401  (look_at: the rigs' camera frame)


def orbit(views, target, radius, elevation_deg, fov_deg, width, height):
    """``views`` cameras on a sphere around ``target``: azimuth in even steps (golden-angle offset),
    elevation alternating through the given [low, high] range."""
    target = np.asarray(target, np.float64)
    lo, hi = elevation_deg
    cams = []
    for k in range(views):
        az = 2 * np.pi * k / views
        el = np.radians(lo + (hi - lo) * ((k * 0.618034) % 1.0))
        pos = target + radius * np.array([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)])
        cams.append(Camera(look_at(pos, target), fov_deg, width, height))
    return cams


def forward_grid(views, centre, target, spread, fov_deg, width, height):
    """``views`` cameras on a jittered grid in the plane through ``centre`` facing ``target``, spread
    over ``spread`` = (width, height) in world units, all looking parallel to centre -> target."""
    centre, target = np.asarray(centre, np.float64), np.asarray(target, np.float64)
    base = look_at(centre, target)
    cols = int(np.ceil(np.sqrt(views * spread[0] / spread[1])))
    rows = int(np.ceil(views / cols))
    rng = np.random.default_rng(0)
    cams = []
    for k in range(views):
        r, c = divmod(k, cols)
        x = ((c + 0.5) / cols - 0.5) * spread[0] + rng.uniform(-0.1, 0.1) * spread[0] / cols
        y = ((r + 0.5) / rows - 0.5) * spread[1] + rng.uniform(-0.1, 0.1) * spread[1] / rows
        m = base.copy()
        m[:3, 3] = centre + x * base[:3, 0] + y * base[:3, 1]
        cams.append(Camera(m, fov_deg, width, height))
    return cams


def path(positions, targets, fov_deg, width, height):
    """One camera per position, each looking at its target: a hand-held rig (arcs, uneven spacing, a
    wandering aim), written out as points because no formula draws it."""
    return [Camera(look_at(p, t), fov_deg, width, height) for p, t in zip(positions, targets)]
