"""Object masks for every view from the masks of a few views, or from a world-space box.

Both start from the full field's surface: in each view v, pixel i with opacity above a half has the
surface point x = o + D_v(i) d (D_v: the full field's depth, distance along the pixel's ray, in world
units whatever the scene space). The mask of view v is the set of pixels whose surface point is the
object's, so whatever stands in front of the object stays unmasked.

* A box [lo, hi] (world units): x is the object's when lo <= x <= hi.
* Masks M_g of a few views g: x is surely the object's when it lies in their visual hull (it projects
  inside M_g, grown by ``grow`` pixels, in every given view whose frame holds it) and some given view
  sees it (its distance from camera g is within ``tol`` of D_g there). It may be the object's when it
  lies in the hull behind the surface every given view sees there, by less than the object's size:
  the object's far side, which no given view sees, or a surface behind the object (the floor it stands
  on), which 3D alone cannot tell apart from few views. The object's size is the diagonal of the box
  around the surface points the given masks cover. With the photos, OpenCV's GrabCut settles the
  "maybe" pixels of each view by colour and image edges (sure pixels fixed, the hull's outside fixed
  as background); without them they count as the object's. Given views keep their given masks.
* Effect masks (the object's shadow, :attr:`~mi_voldis.data.types.Dataset.effects`) of a few views mark
  part of the surfaces, not a solid: x is in it when some given view sees it (as above) inside its mask,
  a union over the given views rather than a hull (:func:`surface_masks`).
"""
import os

import cv2
import numpy as np

from .cameras import pixel_of
from .fit.hull import visual_hull
from .fit.visibility import pixel_points
from .metrics import dilate, iou
from .render.surface import median_depth


def surfaces(integrator, cameras):
    """Per camera, the full field's median depth (H, W) and where its pixels have one (H, W) bool
    (:func:`~mi_voldis.render.surface.median_depth`: unlike the expected depth, haze and half-transparent
    voxels do not pull it, so the surfaces of different views agree)."""
    return [median_depth(integrator, cam) for cam in cameras]


def _points(camera, depth, valid):
    pixels = np.flatnonzero(valid)
    return pixels, pixel_points(camera, depth, pixels)


def box_masks(cameras, surf, lo, hi):
    """Per view, the pixels whose surface point lies in the world box [lo, hi]."""
    out = []
    for cam, (depth, valid) in zip(cameras, surf):
        pixels, x = _points(cam, depth, valid)
        m = np.zeros(depth.size, bool)
        m[pixels[np.all((x >= lo) & (x <= hi), axis=1)]] = True
        out.append(m.reshape(depth.shape))
    return out


def _depth_gap(points, camera, depth):
    """Per point: its distance from ``camera`` minus the surface distance the camera sees at its pixel
    (NaN where it is outside the frame or behind the camera)."""
    ix, iy, ok = pixel_of(camera, points)
    gap = np.full(len(points), np.nan)
    dist = np.linalg.norm(points - np.asarray(camera.to_world)[:3, 3], axis=1)
    gap[ok] = dist[ok] - depth[iy[ok], ix[ok]]
    return gap, dist


def view_masks(cameras, surf, given, grow=0, tol=0.05, images=None):
    """Per view, the object's visible pixels from ``given`` {view index: mask (H, W) bool} (see the
    module docstring); with ``images``, each view's undecided pixels are settled by colour
    (:func:`settle_by_colour`)."""
    g_views = sorted(given)
    g_cams = [cameras[g] for g in g_views]
    g_masks = np.stack([given[g] for g in g_views])
    seeds = np.concatenate([pixel_points(cameras[g], surf[g][0], np.flatnonzero(given[g] & surf[g][1]))
                            for g in g_views])
    size = float(np.linalg.norm(np.percentile(seeds, 98, axis=0) - np.percentile(seeds, 2, axis=0))) if len(
        seeds) else 0.0
    out = []
    for cam, (depth, valid) in zip(cameras, surf):
        pixels, x = _points(cam, depth, valid)
        inside = visual_hull(x, g_cams, g_masks, grow, 1.0)
        seen = np.zeros(len(x), bool)
        behind_all = np.ones(len(x), bool)
        for g in g_views:
            gap, dist = _depth_gap(x, cameras[g], surf[g][0])
            framed = np.isfinite(gap)  # a view without the point in its frame says nothing
            seen[framed] |= np.abs(gap[framed]) <= tol * dist[framed]
            behind_all[framed] &= (gap[framed] > tol * dist[framed]) & (gap[framed] < size)
        sure = np.zeros(depth.size, bool)
        maybe = np.zeros(depth.size, bool)
        sure[pixels[inside & seen]] = True
        maybe[pixels[inside & behind_all & ~seen]] = True
        sure, maybe = sure.reshape(depth.shape), maybe.reshape(depth.shape)
        v = len(out)
        if v in given:
            out.append(given[v])
        elif images is not None:
            out.append(settle_by_colour(images[v], sure, maybe))
        else:
            out.append(sure | maybe)
    return out


def settle_by_colour(image, sure, maybe, iterations=5):
    """Object mask of one view whose pixels are ``sure`` (a given view sees them on the object),
    ``maybe`` (the object's far side, or a surface behind it: 3D cannot tell) or background: OpenCV's
    GrabCut (colour models of object and background, and image edges) decides the ``maybe`` pixels."""
    gc = np.full(sure.shape, cv2.GC_BGD, np.uint8)
    gc[maybe] = cv2.GC_PR_FGD
    gc[sure] = cv2.GC_FGD
    ring = dilate(sure | maybe, 3) & ~(sure | maybe)
    gc[ring] = cv2.GC_PR_BGD
    img = np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)[..., ::-1].copy()
    bgd, fgd = np.zeros((1, 65), np.float64), np.zeros((1, 65), np.float64)
    try:
        cv2.grabCut(img, gc, None, bgd, fgd, iterations, cv2.GC_INIT_WITH_MASK)
    except cv2.error:  # too few pixels of one kind for a colour model: keep the 3D answer
        return sure | maybe
    return (gc == cv2.GC_FGD) | (gc == cv2.GC_PR_FGD)


def view_index(ds, key):
    """The view named ``key``: an image file name, its stem, or an index."""
    for k, name in enumerate(ds.names):
        if key in (name, os.path.splitext(name)[0]):
            return k
    if key.isdigit() and int(key) < len(ds.names):
        return int(key)
    raise ValueError(f"{ds.root}: no view named '{key}' (views are named like {ds.names[0]})")


def surface_masks(cameras, surf, given, tol=0.05):
    """Per view, the pixels whose surface point some view of ``given`` {view index: mask (H, W) bool} sees
    inside its mask (its distance from that camera within ``tol`` of the surface distance there): a
    patch of the surfaces, such as the object's shadow. Given views keep their given masks."""
    out = []
    for v, (cam, (depth, valid)) in enumerate(zip(cameras, surf)):
        if v in given:
            out.append(given[v])
            continue
        pixels, x = _points(cam, depth, valid)
        marked = np.zeros(len(x), bool)
        for g, mask in given.items():
            gap, dist = _depth_gap(x, cameras[g], surf[g][0])
            ix, iy, ok = pixel_of(cameras[g], x)
            ok[ok] &= mask[iy[ok], ix[ok]]
            marked |= ok & (np.abs(np.nan_to_num(gap, nan=np.inf)) <= tol * dist)
        m = np.zeros(depth.size, bool)
        m[pixels[marked]] = True
        out.append(m.reshape(depth.shape))
    return out


def given_mask(path, size):
    """The object mask of ``path`` given to :func:`make_masks` for a view of ``size`` (H, W), refused
    in one line naming the file when it is not one: another size, empty, covering every pixel, a colour
    image, or a grey one with many pixels neither black nor white (a photo given as a mask)."""
    from .data.images import _read, mask_values, read_mask
    raw = _read(path, "mask", raw=True)
    if raw.ndim == 3 and raw.shape[2] >= 3:
        rgb = raw[..., :3].astype(np.float64)
        spread = (rgb.max(axis=2) - rgb.min(axis=2)) / (1.0 if raw.dtype.kind == "f" else np.iinfo(raw.dtype).max)
        if np.mean(spread > 0.1) > 0.01:
            raise ValueError(f"{path}: a colour image, not a mask ({100 * np.mean(spread > 0.1):.0f}% of its pixels "
                             "are coloured); a mask is white (or 1) on the object, black elsewhere")
    values, _ = mask_values(path)
    grey = float(np.mean((values > 0.1) & (values < 0.9)))
    if grey > 0.05:
        raise ValueError(f"{path}: not a mask: {100 * grey:.0f}% of its pixels are neither black nor white (a photo?); "
                         "a mask is white (or 1) on the object, black elsewhere")
    mask = read_mask(path, "white")
    if mask.shape != tuple(size):
        raise ValueError(f"{path}: mask is {mask.shape[1]}x{mask.shape[0]} but the images are {size[1]}x{size[0]}")
    if not mask.any():
        raise ValueError(f"{path}: the mask is empty")
    if mask.all():
        raise ValueError(f"{path}: the mask covers every pixel; it must leave some of the view as background")
    return mask


def check_run_dataset(run_dir, dataset):
    """Refuses a fitted run whose ``config.json`` records another dataset than ``dataset`` (compared as
    real paths): its surfaces are another scene's."""
    import json
    path = os.path.join(run_dir, "config.json")
    try:
        with open(path, encoding="utf-8") as f:
            recorded = json.load(f).get("dataset", {}).get("path")
    except (OSError, ValueError, AttributeError) as e:
        raise ValueError(f"{path}: cannot read the run's record ({e})") from None
    if recorded and os.path.realpath(recorded) != os.path.realpath(dataset):
        raise ValueError(f"{run_dir}: the run was fitted on {recorded}, not on {dataset}; give --run a fit of this "
                         "dataset (or a new folder to fit it into)")


def check_box_seen(cameras, lo, hi, samples=16):
    """Refuses a world box [lo, hi] that no camera has in its frame (``samples``^3 points of it tried),
    before any fit: no view could mask any of it."""
    axes = [np.linspace(a, b, samples) for a, b in zip(lo, hi)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    if not any(pixel_of(cam, points)[2].any() for cam in cameras):
        raise ValueError(f"--box {','.join(f'{v:g}' for v in (*lo, *hi))}: no view has any of the box in its frame "
                         f"(world units, the dataset's poses; the cameras stand around "
                         f"{', '.join(f'{v:.3g}' for v in np.mean([c.to_world[:3, 3] for c in cameras], axis=0))})")


MASK_FOLDERS = ("masks", "effects")  # the folders of a dataset make_masks may replace (the loaders read them)


def mask_inputs(dataset, run_dir, given):
    """What the masks' folder must stay apart from: the dataset's files but its mask folders
    (:func:`~mi_voldis.io.run_folder.dataset_inputs`: ``DATASET/masks`` may be replaced,
    ``DATASET/images`` or the dataset itself not), the run and the given mask files."""
    from .io.run_folder import dataset_inputs
    return dataset_inputs(dataset, MASK_FOLDERS) + [(run_dir, "run")] + [(p, "given mask") for p in
                                                                         (given or {}).values()]


def mask_names(names, dataset):
    """The mask file of each view, ``<image stem>.png`` (the loaders match masks to images by stem); two
    images of one stem would write one file, so they raise ``ValueError`` naming both."""
    out, seen = [], {}
    for name in names:
        stem = os.path.splitext(os.path.basename(name))[0]
        if stem in seen:
            raise ValueError(f"{dataset}: images {seen[stem]} and {name} share the stem '{stem}', so their masks "
                             f"would be one file ({stem}.png); rename one of them")
        seen[stem] = name
        out.append(stem + ".png")
    return out


def make_masks(dataset, run_dir, out, given=None, box=None, fmt="auto", factor=None, cfg=None, progress=True,
               effects=False, resume=False, restart=False):
    """Write an object mask for every view of the dataset at ``dataset`` into the folder ``out``
    (``<image stem>.png``, white = object: what the loaders read from ``DATASET/masks/``), from
    ``given`` {view name: mask file} or a world ``box`` (lo, hi), through the full field of the run
    ``run_dir`` (fitted there first when it does not exist yet); with ``effects``, the given masks are
    effect masks (the object's shadow) and so are those written (:func:`surface_masks`; the loaders read
    them from ``DATASET/effects/``). Returns a summary; with ground-truth coverage in the dataset, the
    object masks' IoU against it. ``resume`` / ``restart``: of the fit into ``run_dir``. Checked before
    any work: ``out`` apart from the dataset's files (a folder of masks inside it is what the loaders
    read), the run and the given masks; the run apart from the dataset."""
    from .data import check_rig, load_dataset
    from .fit.run import run_fit
    from .io.images import write_png
    from .io.run_folder import check_output, dataset_inputs, staged
    from .tasks.base import FittedRun
    fitted = os.path.isfile(os.path.join(run_dir, "scene.xml"))
    if not fitted:
        check_output(run_dir, dataset_inputs(dataset), resume, restart, program="train")
    inputs = mask_inputs(dataset, run_dir, given)
    check_output(out, inputs, program="make_masks")
    if fitted:
        check_run_dataset(run_dir, dataset)
    ds = load_dataset(dataset, fmt, holdout=0, factor=factor)
    mask_names(ds.names, dataset)  # before the fit: two views whose masks would be one file are refused
    masks, named = {}, {}
    for key, path in (given or {}).items():
        v = view_index(ds, key)
        if v in named:
            raise ValueError(f"{path}: view {ds.names[v]} is given twice ({named[v]} and {path}); give each view once")
        named[v] = path
        masks[v] = given_mask(path, ds.size)
    if box is not None:
        check_box_seen(ds.cameras, *box)
    if not fitted:
        check_rig(ds)
        run_fit(dataset, run_dir, cfg, resume, progress, fmt, factor=factor, restart=restart)
    integrator = FittedRun(run_dir, dataset).integrator()
    surf = surfaces(integrator, ds.cameras)
    if box is not None:
        result = box_masks(ds.cameras, surf, *box)
        if not any(m.any() for m in result):
            raise ValueError(f"--box {','.join(f'{v:g}' for v in (*box[0], *box[1]))}: no view's surface lies in the "
                             "box (world units, the dataset's poses); nothing written")
    elif effects:
        result = surface_masks(ds.cameras, surf, masks)
    else:
        result = view_masks(ds.cameras, surf, masks, images=ds.images)
    with staged(out, inputs=inputs, made_by="make_masks") as stage:
        for name, m in zip(mask_names(ds.names, dataset), result):
            write_png(os.path.join(stage, name), np.where(m, 255, 0).astype(np.uint8))
    summary = {"masks": out, "views": len(result), "object_share": float(np.mean([m.mean() for m in result])),
               "empty_views": int(sum(not m.any() for m in result))}
    if ds.coverage is not None and not effects:
        scores = [iou(m, c > 0.5) for v, (m, c) in enumerate(zip(result, ds.coverage)) if v not in masks]
        summary["iou_vs_coverage"] = float(np.nanmean(scores))
    return summary
