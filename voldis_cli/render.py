"""Render a voldis scene to layered EXRs and PNG previews.

    python scripts/render.py SCENE.xml --out DIR [--spp N] [--width W --height H] [--variant V]
    python scripts/render.py RUN/scene.xml --cameras DATASET --split test --out DIR
    python scripts/render.py RUN/<task>/scene.xml --path orbit|spiral|interpolate|camera_path.json --frames N --out DIR

With --cameras, the views (split, downscale factor) are those the run was fitted with, read from the
config.json beside SCENE.xml when there is one.

Writes, per sensor of the scene (or per camera of a dataset split), DIR/<name>.exr (R, G, B, A,
depth.Z, full.*, bg.*, fg.*; colours in linear light, mi_voldis/compositing.py) and PNG previews
DIR/<name>_<layer>.png. With --path: DIR/frame_NNNN.exr and DIR/<layer>.mp4 (needs imageio-ffmpeg:
pip install .[video]; without it DIR/<layer>.gif). The path is made from the training views of the
capture the run was fitted on (or --cameras DATASET).

DIR is written whole (DIR.partial, then swapped in) and replaces an earlier render; it may not be,
hold or lie inside the scene file, the files it refers to or the dataset read.
"""
import argparse
import os
import sys

from .boundary import add_debug, positive, run


def run_record(folder):
    """The dataset record of the run holding the scene: the config.json beside it, or, for a task's
    scene (RUN/<task>/scene.xml), the run's one folder up; None when there is none."""
    import json
    for candidate in (folder, os.path.dirname(folder)):
        try:
            with open(os.path.join(candidate, "config.json")) as f:
                record = json.load(f).get("dataset")
        except (OSError, ValueError, AttributeError):
            continue
        if isinstance(record, dict) and record.get("path"):
            return record
    return None


def camera_path(args, record):
    """The cameras of ``--path``: a nerfstudio camera_path.json, or a path made from the capture's
    training views (``--cameras DATASET``, else the run's own dataset)."""
    from mi_voldis import camera_paths
    if args.path.endswith(".json"):
        capture = args.cameras or (record or {}).get("path")
        return camera_paths.read_nerfstudio_path(args.path, args.dataparser_transforms, capture)
    if args.path not in camera_paths.PATHS:
        raise ValueError(f"--path must be {', '.join(camera_paths.PATHS)} or a camera_path.json, got '{args.path}'")
    from mi_voldis.data import load_dataset
    from mi_voldis.tasks.base import load_recorded
    if args.cameras:
        ds = load_recorded(record, args.cameras) if record else load_dataset(args.cameras)
    elif record:
        ds = load_recorded(record)
    else:
        raise ValueError(f"{args.scene}: no run config.json beside it to find the capture; give --cameras DATASET")
    return camera_paths.make_path(args.path, [ds.cameras[v] for v in ds.train], args.frames, ds.near_far)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="Mitsuba XML scene with a 'voldis' integrator")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--spp", type=positive, default=None, help="samples per pixel (default: the scene's)")
    ap.add_argument("--width", type=positive, help="override the films' width")
    ap.add_argument("--height", type=positive, help="override the films' height")
    ap.add_argument("--cameras", help="render from this dataset's cameras instead of the scene's sensors")
    ap.add_argument("--split", default="test", choices=("train", "test", "all"), help="views of --cameras")
    ap.add_argument("--path", metavar="KIND", help="a camera path instead: orbit, spiral, interpolate (through the "
                    "capture's views) or a nerfstudio camera_path.json; writes an EXR sequence and a video")
    ap.add_argument("--frames", type=positive, default=60, help="frames of --path orbit / spiral / interpolate")
    ap.add_argument("--fps", type=positive, default=None,
                    help="video frame rate (default: a camera_path.json's frames / seconds, else 24)")
    ap.add_argument("--layer", default="composite", choices=("composite", "full", "bg", "fg"),
                    help="the layer shown in the video")
    ap.add_argument("--dataparser-transforms", help="nerfstudio's dataparser_transforms.json for a camera_path.json")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default: llvm_ad_rgb)")
    ap.add_argument("--quiet", action="store_true", help="print nothing but errors")
    add_debug(ap)
    args = ap.parse_args(argv)
    if (args.width is None) != (args.height is None):
        ap.error("--width and --height go together")

    os.environ["MI_VOLDIS_VARIANT"] = args.variant  # chosen before the first import of mi_voldis
    from mi_voldis.io.run_folder import check_output, dataset_inputs, scene_files, staged
    record = run_record(os.path.dirname(os.path.abspath(args.scene)))
    inputs = [(p, "scene's file") for p in scene_files(args.scene)]
    for path in (args.cameras or (record or {}).get("path"),):
        inputs += dataset_inputs(path) if path else []
    for path in (args.dataparser_transforms, args.path if args.path and args.path.endswith(".json") else None):
        inputs += [(path, "input file")] if path else []
    check_output(args.out, inputs, program="render")
    from mi_voldis.export import render_path, render_scene_files
    from mi_voldis.scene import load_scene

    scene = load_scene(args.scene)
    size = (args.width, args.height) if args.width else None
    cameras = None
    if args.path:
        path_cameras = camera_path(args, record)
        if size:
            from mi_voldis.cameras import Camera
            path_cameras = [Camera(c.to_world, c.fov_x, *size, c.principal) for c in path_cameras]
        check_render_size("--width/--height" if size else args.path, scene,
                          [(c.width, c.height, args.spp or 1) for c in path_cameras], kept=VIDEO_BYTES)
        fps = args.fps
        if fps is None:
            from mi_voldis.camera_paths import nerfstudio_fps
            fps = (nerfstudio_fps(args.path) if args.path.endswith(".json") else None) or 24
        with staged(args.out, inputs=inputs, made_by="render") as stage:
            exrs, video = render_path(scene, stage, path_cameras, args.spp, args.layer, fps)
        if not args.quiet:
            print(f"{len(exrs)} frames: {args.out}/frame_NNNN.exr\nvideo: {final(video, stage, args.out)}")
        return
    if args.cameras:
        from mi_voldis.data import load_dataset
        from mi_voldis.tasks.base import load_recorded
        ds = load_recorded(record, args.cameras) if record else load_dataset(args.cameras)
        views = range(len(ds.cameras)) if args.split == "all" else (ds.test if args.split == "test" else ds.train)
        if not len(views):
            raise ValueError(f"{args.cameras}: no {args.split} views to render")
        cameras = [(os.path.splitext(ds.names[v])[0].replace("/", "_"), ds.cameras[v]) for v in views]
        names = [n for n, _ in cameras]
        twice = next((n for k, n in enumerate(names) if n in names[:k]), None)
        if twice:  # one file for two views: refused before anything is rendered
            raise ValueError(f"{args.cameras}: two views are both named '{twice}' without their extension, so their "
                             f"renders ({twice}.exr) would be one file; rename one of the images")
        check_render_size("--width/--height" if size else args.cameras, scene,
                          [(*(size or (c.width, c.height)), args.spp or 1) for _, c in cameras])
    elif not scene.sensors():
        raise ValueError(f"{args.scene}: the scene has no sensor; give --cameras DATASET")
    else:
        check_render_size("--width/--height" if size else args.scene, scene,
                          [(*(size or [int(v) for v in s.film().size()]), args.spp or s.sampler().sample_count())
                           for s in scene.sensors()])
    with staged(args.out, inputs=inputs, made_by="render") as stage:
        written = render_scene_files(scene, stage, spp=args.spp, size=size, cameras=cameras)
    for path in written if not args.quiet else ():
        print(final(path, stage, args.out))


# Memory of a render per pixel and raw channel (RGB, the film's alpha, the integrator's AOVs): the film,
# the rendered tensor, its NumPy copy and the composited layers. A render of 256^2 to 2048^2 pixels
# (21 channels, any spp: the march is one fused kernel whose rays are never stored) peaked at 25 bytes
# per pixel and channel above the loaded scene; 32 leaves a margin.
RENDER_BYTES = 32
VIDEO_BYTES = 3  # a path's frames are kept for the video: 8-bit RGB per pixel and frame


def check_render_size(source, scene, sizes, kept=0):
    """Refuse a render that cannot fit before it starts (:mod:`mi_voldis.io.limits`): ``sizes`` the
    (width, height, spp) of every image rendered (one after another), ``kept`` bytes per pixel kept of
    every image until the end. ``source`` names what set the size (the flags, scene or dataset)."""
    from mi_voldis.io.limits import check_entries, check_memory
    channels = 4 + len(scene.integrator().aov_names())
    # Mitsuba's wavefront holds a sample per pixel and spp, its film a value per pixel and channel
    # plus the filter weight: each one Dr.Jit array
    w, h, spp = max(sizes, key=lambda s: s[0] * s[1] * max(s[2], channels + 1))
    check_entries(f"{source}: a {w}x{h} render ({spp} spp, {channels} channels)", w * h * max(spp, channels + 1))
    w, h, _ = max(sizes, key=lambda s: s[0] * s[1])
    kept = sum(a * b * kept for a, b, _ in sizes)
    check_memory(f"{source}: a {w}x{h} render", w * h * RENDER_BYTES * channels + kept)


def final(path, stage, out):
    """Where ``path``, written in the staged folder, lies once it is swapped in."""
    return os.path.join(out, os.path.relpath(path, stage))


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
