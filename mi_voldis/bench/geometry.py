"""Where a fitted run puts its weight against the true surfaces of a synthetic scene.

    python -m mi_voldis.bench.geometry RUN [--scene XML] [--views test|train|all] [--layer full|bg]

A radiance field can reproduce its photographs with the wrong geometry: a veil in front of the surfaces,
each training camera's own painted screen. The held-out PSNR sees that only where the views leave the
training path, yet the removal of an object inherits all of it: what the background keeps in front of the
hole is drawn into it. On a dataset rendered from a Mitsuba scene (``make_dataset.py`` copies random and
family scenes to ``DATASET/scene/scene.xml``; ``--scene`` names another, e.g. ``scenes/tabletop.xml``), each
pixel's true distance t_ref is its ray's first hit in that scene (the object in place), and the full field's
weights w_i at distances t_i along the ray split by bands of t_i / t_ref (:data:`BANDS`,
:func:`~mi_voldis.render.surface.weight_bands`). Printed per view and averaged over the views' pixels that
hit something: far in front (veils, screens), just in front, on the surface, behind, and what no sample
holds (T at the ray's end: the field lets the surface through); over the whole view, and around the object
(its mask grown as the removal's score grows it, :data:`~mi_voldis.metrics.SCORE_DILATION`), where the
background is taken apart from it. A far backdrop seen with little parallax may stand 10% off and render
the same, so on forward-facing rigs the whole view's figure is a bound; around the object the rig's
parallax pins the surfaces. With ``--layer bg`` the background layer is measured against the scene without
the object (its shapes removed as ``make_dataset.py`` removes them for the true backgrounds), around the
object being the hole: whether the removal's weight sits on the surface the object hid (#46: no haze in
the hole) or hangs in front of it.
"""
import json
import os
import sys

import numpy as np

# band edges on t / t_ref: far in front (< 0.9), just in front (0.9 .. 0.98), on the surface (within 2% of its
# distance: a voxel or two at the family's 128 x 96 views), behind (>= 1.02)
BANDS = (0.9, 0.98, 1.02)
BAND_NAMES = ("far in front", "just in front", "on the surface", "behind")


def true_depth(scene, camera):
    """Distance along each pixel-centre ray of ``camera`` (H, W) to its first hit in the Mitsuba
    ``scene``; infinity where the ray hits nothing."""
    import mitsuba as mi

    from ..cameras import pixel_rays
    from ..device import from_numpy
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    o, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    si = scene.ray_intersect(mi.Ray3f(from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d)))
    t = np.array(si.t, np.float64)
    return np.where(np.isfinite(t), t, np.inf).reshape(camera.height, camera.width)


def surface_shares(integrator, scene, camera, regions=None, layer="full"):
    """For each region ({name: (H, W) bool}; default the whole view), the mean weight per band of
    :data:`BAND_NAMES`, then the weight no sample holds, over the region's pixels of ``camera`` whose ray
    hits ``scene``, and that pixel count: {name: (shares, count)}."""
    from ..render.surface import weight_bands
    t = true_depth(scene, camera)
    bands = weight_bands(integrator, camera, np.where(np.isfinite(t), t, np.nan), BANDS, layer=layer)
    out = {}
    for name, region in (regions or {"whole": np.ones(t.shape, bool)}).items():
        hit = np.isfinite(t) & region
        per = bands[hit]
        out[name] = ((np.append(per.mean(0), max(0.0, 1.0 - per.sum(1).mean())), int(hit.sum())) if hit.any()
                     else (np.zeros(len(BANDS) + 2), 0))
    return out


def load_truth(xml, layer="full"):
    """The Mitsuba scene of ``xml``; for ``layer`` 'bg' without the object's shapes (those whose id starts
    with the scene's object prefix: its rig JSON's ``object_prefix``, the JSON beside the XML with the same
    stem or ``scene.json``, else 'object')."""
    import mitsuba as mi

    from ..synth import variants
    root = variants.parse(xml)
    if layer == "bg":
        prefix = "object"
        for rig in (os.path.splitext(xml)[0] + ".json", os.path.join(os.path.dirname(xml), "scene.json")):
            if os.path.isfile(rig):
                with open(rig) as f:
                    prefix = json.load(f).get("object_prefix", prefix)
                break
        root = variants.without_object(root, prefix)
    mi.file_resolver().prepend(os.path.dirname(os.path.abspath(xml)))  # its textures, as make_dataset reads them
    return mi.load_string(variants.to_string(root))


def scene_of(dataset, given=None):
    """The Mitsuba XML a dataset was rendered from: ``given``, else ``dataset/scene/scene.xml``; None if
    neither exists."""
    path = given or os.path.join(dataset, "scene", "scene.xml")
    return path if os.path.isfile(path) else None


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    usage = "usage: python -m mi_voldis.bench.geometry RUN [--scene XML] [--views test|train|all] [--layer full|bg]"
    opts = {}
    for key in ("--scene", "--views", "--layer"):
        if key in argv:
            k = argv.index(key)
            if k + 1 >= len(argv):
                raise SystemExit(f"error: {key} needs a value\n{usage}")
            opts[key] = argv[k + 1]
            del argv[k:k + 2]
    if len(argv) != 1 or argv[0].startswith("-"):
        raise SystemExit(usage)
    run = argv[0]
    which = opts.get("--views", "test")
    if which not in ("test", "train", "all"):
        raise SystemExit(f"error: --views {which}: expected test, train or all")
    layer = opts.get("--layer", "full")
    if layer not in ("full", "bg"):
        raise SystemExit(f"error: --layer {layer}: expected full or bg")
    config = os.path.join(run, "config.json")
    try:
        with open(config) as f:
            record = json.load(f).get("dataset")
    except (OSError, ValueError) as e:
        raise SystemExit(f"error: {config}: not a fitted run's settings ({e.__class__.__name__})") from None
    if not isinstance(record, dict) or "path" not in record:
        raise SystemExit(f"error: {config}: no dataset record (not a fitted run's)")
    if not os.path.isdir(record["path"]):
        raise SystemExit(f"error: {record['path']}: the run's dataset is not there ({config} names it)")
    xml = scene_of(record["path"], opts.get("--scene"))
    if xml is None:
        raise SystemExit(f"error: {opts.get('--scene') or record['path']}: no ground-truth scene "
                         f"({'not a file' if '--scene' in opts else 'no scene/scene.xml'}; give --scene, the "
                         "Mitsuba XML the dataset was rendered from)")
    import mi_voldis
    try:
        scene = load_truth(xml, layer)
    except (RuntimeError, ValueError) as e:
        raise SystemExit(f"error: {xml}: Mitsuba cannot load it ({str(e).splitlines()[0][:200]})") from None
    loaded = mi_voldis.load_run(run)
    ds, integrator = loaded.dataset, loaded.integrator()
    views = {"test": list(ds.test), "train": list(ds.train), "all": list(ds.test) + list(ds.train)}[which]
    if not views:
        raise SystemExit(f"error: {record['path']}: no {which} views")
    from ..metrics import dilate, score_dilation
    what = ("the full field's weight against" if layer == "full"
            else "the background layer's weight against the object-free")
    print(f"{run}: {what} {xml}, {which} views (t / t_true: far in front < {BANDS[0]}, "
          f"just in front < {BANDS[1]}, on the surface < {BANDS[2]}, behind; none: what no sample holds)")
    print("| view | pixels | " + " | ".join(BAND_NAMES) + " | none |")
    print("|---" * (len(BAND_NAMES) + 3) + "|")
    sums = {}
    for v in views:
        camera = ds.cameras[v]
        regions = {"whole": np.ones((camera.height, camera.width), bool)}
        if ds.masks is not None and ds.masks[v].any():
            hole = dilate(ds.masks[v], score_dilation(ds.size))
            regions["around the object" if layer == "full" else "the hole"] = hole
        for name, (shares, n) in surface_shares(integrator, scene, camera, regions, layer).items():
            total, pixels = sums.get(name, (0.0, 0))
            sums[name] = (total + shares * n, pixels + n)
            print(f"| {v} | {name} | " + " | ".join(f"{x:.3f}" for x in shares) + " |", flush=True)
    for name, (total, pixels) in sums.items():
        print(f"| all | {name} | " + " | ".join(f"{x:.3f}" for x in total / max(pixels, 1)) + " |")


if __name__ == "__main__":
    main()
