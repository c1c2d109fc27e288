"""The 2D colour prior of the ``guided`` background: every view's own inpainting, as a weak target.

What some view sees unmasked the masked loss L_bg reconstructs; what no view sees it leaves to the
start of the fit (the harmonic fill of the hull, :func:`~mi_voldis.fit.background.start_harmonic`),
which blends the colours around the hull through its whole volume and so leaves a translucent ghost of
the object's silhouette. The prior adds, on the masked pixels of every masked training view i,

    L_prior = lambda * mean_i ||x^bg_i - I_i||^2,

where I_i is view i's photo inpainted in 2D inside its mask (grown by ``dilation``: edge pixels mix the
object in) and its effect mask if the dataset has one (the object's shadow: there the photos show the
object's effect, and L_bg leaves those pixels to the prior), as SPIn-NeRF supervises with per-view
inpaintings. The views' inpaintings disagree where no
view sees the background, and the field settles on their average, consistent by construction; where
some view does see it, that view's unmasked rays (weight 1 against ``lambda``) decide.

An occluder in front of the object is no source for the inpainting: ring pixels around the mask whose
full-field surface lies nearer than ``nearer`` times the object's (the median of its median depths)
join the 2D hole, so the fill continues the surfaces behind the object, not the occluder's colour
(:func:`inpainting_hole`). The prior's weight applies on the grown mask alone, not on that ring.
"""
import dataclasses
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..inpaint2d import inpainter, inpainter_name
from ..metrics import dilate
from ..raybank import RayBank
from ..render.surface import median_depth
from .fields import fit_integrator


def inpainting_hole(region, depth, hit, object_mask, ring, nearer=0.9):
    """The pixels a 2D inpainter must fill for a prior on ``region`` (H, W bool): the region itself and,
    within ``ring`` pixels of it, what stands in front of the object (median depth ``depth`` where
    ``hit``, nearer than ``nearer`` times the object's median depth over ``object_mask``)."""
    inside = object_mask & hit
    if not inside.any():
        return region.copy()
    front = nearer * float(np.median(depth[inside]))
    return region | (dilate(region, ring) & hit & (depth < front))


def colour_prior(inputs, state, fill, dilation=0.01, ring=0.03, nearer=0.9, depths=None):
    """The prior's rays: a :class:`~mi_voldis.raybank.RayBank` over the training views (same order as the
    fit's bank, so ray views index the same colour corrections) whose colours are each masked view's
    photo inpainted with ``fill`` (an inpainter of :mod:`mi_voldis.inpaint2d`) in its mask grown by
    ``dilation`` of the diagonal (occluders within ``ring`` of the diagonal left out of the sources,
    :func:`inpainting_hole`), and the flat indices of those masked pixels. Records the inpainter used in
    ``state.prior`` (metrics.json's ``bg_prior.inpainter``). ``depths``: the full field's median depth maps
    by view (NaN where none), read and filled (:func:`~mi_voldis.fit.lift.training_depths`)."""
    ds = inputs.ds
    diag = np.hypot(*ds.size)
    grow, around = int(np.ceil(dilation * diag)), int(np.ceil(ring * diag))
    train = list(ds.train)
    masked = set(int(v) for v in ds.masked_train)
    images = ds.images[train].copy()
    region = np.zeros((len(train),) + tuple(ds.size), bool)
    paint = inpainter(fill)
    state.prior = {**(state.prior or {}), "inpainter": inpainter_name(fill)}
    integrator = fit_integrator(inputs, state)
    holes = {}
    for k, v in enumerate(train):
        if v not in masked:
            continue
        region[k] = dilate(ds.masks[v], grow) | (ds.effects[v] if ds.effects is not None else False)
        depth = view_depth(integrator, ds, v, depths)
        holes[k] = inpainting_hole(region[k], np.nan_to_num(depth), np.isfinite(depth), ds.masks[v], around, nearer)
    # the built-in inpainters are pure functions of their view, OpenCV's and NumPy's run without the GIL, and
    # FSR is single-threaded (statue: 2.2 s a view): the views are painted on every core. A caller's own
    # inpainter (a callable, say a learned model) is called one view at a time, as it may not be thread-safe.
    workers = 1 if callable(fill) else min(len(holes), os.cpu_count() or 1) or 1
    with ThreadPoolExecutor(workers) as pool:
        for k, image in zip(holes, pool.map(lambda k: paint(np.clip(ds.images[train[k]], 0, 1), holes[k]), holes)):
            images[k] = image
    inpainted = dataclasses.replace(ds, images=images, cameras=[ds.cameras[v] for v in train], masks=region,
                                    split=np.array(["train"] * len(train)), masked=None, effects=None,
                                    ignore=None if ds.ignore is None else ds.ignore[train])
    return RayBank(inpainted, np.arange(len(train))), np.flatnonzero(region.reshape(-1)).astype(np.uint32)


def view_depth(integrator, ds, v, memo=None):
    """The full field's median depth map of view ``v`` of ``ds`` (NaN where no surface), rendered with
    ``integrator``; ``memo``: a dict of such maps by view, read and filled."""
    if memo is not None and v in memo:
        return memo[v]
    depth, hit = median_depth(integrator, ds.cameras[v])
    depth = np.where(hit, depth, np.nan)
    if memo is not None:
        memo[v] = depth
    return depth
