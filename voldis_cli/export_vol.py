"""Export a fitted field as dense world-space .vol grids for Mitsuba's own gridvolume / heterogeneous medium.

    python scripts/export_vol.py RUN/scene.xml --out DIR [--field full|bg] [--region x0,y0,z0,x1,y1,z1]
                                 [--resolution N | NX,NY,NZ]

Writes DIR/<field>_sigma_t.vol (density per world unit), DIR/<field>_albedo.vol (the view-independent
colour) and DIR/<field>_gridvolume.xml (a cube holding a heterogeneous medium over them, volpath, a
constant environment and the scene's first camera, a complete scene for `mitsuba` or mi.render; see
mi_voldis/field/dense_export.py for how contracted and NDC densities are converted). Default region: the
field's box (world space) or the inner cube of a contracted space; NDC scenes need --region. Default
resolution: 128 values along the region's longest side, the others in proportion. DIR is written
whole (DIR.partial, then swapped in) and replaces an earlier export; it may not be, hold or lie inside
the scene file or the files it refers to.
"""
import argparse
import os
import sys

from .boundary import add_debug, positive, run


def numbers(text, count, flag, kind=float):
    try:
        values = [kind(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in count:
        raise argparse.ArgumentTypeError(f"--{flag} expects {' or '.join(map(str, count))} comma-separated numbers, "
                                         f"got '{text}'")
    return values


def _box(values):
    return ",".join(f"{v:g}" for v in values)


def check_region(region, field, space, name):
    """Refuse a ``--region`` holding no point of the field (outside its box the export is all zeros).
    World space: the region against the field's world box. NDC: a 9^3 lattice of the region's points
    mapped into the field. A contracted space maps the whole world into the field: any region holds it."""
    import numpy as np
    lo, hi = np.array(region[:3]), np.array(region[3:])
    if space.is_world:
        corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], np.float64)
        world = corners @ field.to_world[:3, :3].T + field.to_world[:3, 3]
        box_lo, box_hi = world.min(0), world.max(0)
        if np.any(lo >= box_hi) or np.any(hi <= box_lo):
            raise ValueError(f"--region {_box(region)} lies outside the scene's box {_box(box_lo)} to "
                             f"{_box(box_hi)} (field '{name}'): the export would be all zeros")
    elif not space.is_curved:
        axes = [np.linspace(lo[a], hi[a], 9) for a in range(3)]
        points = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
        with np.errstate(all="ignore"):  # points behind the reference camera have no NDC position
            p = space.from_world_np(points)
            local = p @ field.world_to_local[:3, :3].T + field.world_to_local[:3, 3]
        if not np.any(np.all((local >= 0) & (local <= 1), axis=1)):
            raise ValueError(f"--region {_box(region)} holds no point of field '{name}' (its box in NDC "
                             f"space): the export would be all zeros")


# Memory of an export per value: sigma_t (4 bytes) and albedo (12) held whole, and the albedo's copy
# while it is written (12); then a z-slab of points in float64 and their lookups, under 256 bytes each.
EXPORT_BYTES = 32
SLAB_BYTES = 256


def check_export_size(resolution):
    """Refuse an export that cannot fit before sampling (:mod:`mi_voldis.io.limits`); a slab holds at
    least one z-plane of points, each coordinate one Dr.Jit array."""
    from mi_voldis.field.dense_export import SLAB_VERTICES
    from mi_voldis.io.limits import check_entries, check_memory
    nx, ny, nz = resolution
    what = f"--resolution: a {nx}x{ny}x{nz} export"
    check_entries(what, nx * ny)
    check_memory(what, nx * ny * nz * EXPORT_BYTES + max(SLAB_VERTICES, nx * ny) * SLAB_BYTES)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="scene.xml of a run (scripts/train.py) or a task (scripts/optimize.py)")
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--field", default="full", help="which field: full or bg (default: full)")
    ap.add_argument("--region", type=lambda t: numbers(t, (6,), "region"), help="world box x0,y0,z0,x1,y1,z1")
    ap.add_argument("--resolution", type=lambda t: [positive(v) for v in numbers(t, (1, 3), "resolution", str)],
                    help="values along the longest side (N) or per axis (NX,NY,NZ); default 128")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default: llvm_ad_rgb)")
    ap.add_argument("--quiet", action="store_true", help="print nothing but errors")
    add_debug(ap)
    args = ap.parse_args(argv)
    os.environ["MI_VOLDIS_VARIANT"] = args.variant  # chosen before the first import of mi_voldis
    import numpy as np

    from mi_voldis.field.dense_export import export_dense, source_sensor, write_export
    from mi_voldis.io.run_folder import check_output, scene_files, staged
    from mi_voldis.scene import load_scene

    inputs = [(p, "scene's file") for p in scene_files(args.scene)]
    check_output(args.out, inputs, program="export_vol")

    integrator = load_scene(args.scene).integrator()
    fields = integrator.fields
    if args.field not in fields:
        raise ValueError(f"{args.scene}: no field '{args.field}' (it has {', '.join(sorted(fields))})")
    field, space = fields[args.field], integrator.space
    if args.region is not None:
        lo, hi = np.array(args.region[:3]), np.array(args.region[3:])
        if not np.all(hi > lo):
            raise ValueError(f"--region needs x0 < x1, y0 < y1, z0 < z1, got {args.region}")
        check_region(args.region, field, space, args.field)
    elif space.kind == "ndc":
        raise ValueError(f"{args.scene}: the fields live in NDC space, which has no finite world box: give --region")
    else:
        corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], np.float64)
        if space.is_curved:  # the inner cube of the contraction
            world = space.to_world_np(np.clip(2 * corners - 1, -1, 1))
        else:
            world = corners @ field.to_world[:3, :3].T + field.to_world[:3, 3]
        lo, hi = world.min(0), world.max(0)
    size = hi - lo
    if args.resolution is None or len(args.resolution) == 1:
        n = args.resolution[0] if args.resolution else 128
        resolution = [max(1, int(round(n * s / size.max()))) for s in size]
    else:
        resolution = args.resolution
    check_export_size(resolution)
    sigma, albedo = export_dense(field, space, lo, hi, resolution)
    with staged(args.out, inputs=inputs, made_by="export_vol") as stage:
        path = write_export(stage, args.field, sigma, albedo, lo, hi, source=os.path.abspath(args.scene),
                            sensor=source_sensor(args.scene))
    if not args.quiet:
        print(os.path.join(args.out, os.path.relpath(path, stage)))


def entry():
    """The console command (``[project.scripts]`` in pyproject.toml)."""
    sys.exit(run(main))
