"""Camouflage: the object keeps its shape and takes the colours of what is behind it (paper Sec. 3.2).

A foreground colour field c_cam over the object's region (a grid over the box where the full and
background fields differ, not the whole scene) replaces c_fg in the composite; its density is unused,
so the foreground weights w'_fg = w_fg, and with them every depth, are unchanged by construction.
Only that colour grid is optimised, with :func:`mi_voldis.losses.camouflage_loss`: the composite
against the background render of the same rays.
"""
import mitsuba as mi
import numpy as np

from ..losses import camouflage_loss
from ..metrics import psnr
from ..optim.adam import Adam
from ..render.views import render_camera
from .base import EditProblem, edit_field, run_optimisation


def colour_field(run, resolution):
    """A foreground colour field over the object's box (raw colour 0: grey)."""
    lo, hi = run.foreground_box()
    return mi.load_dict(edit_field(lo, hi, resolution))


def depth_and_errors(run, integrator, views):
    """Composite depth and the composite's error to the background render, per view."""
    out = {}
    for v in views:
        r = render_camera(integrator, run.dataset.cameras[v], ("composite", "bg"))
        out[v] = (r["composite"][2], psnr(np.clip(r["composite"][0], 0, 1), np.clip(r["bg"][0], 0, 1)), r)
    return out


def run(run, output, progress=True):
    s = output.settings
    views = list(run.dataset.test)
    before = depth_and_errors(run, run.integrator(composition=s.composition), views)
    cam = colour_field(run, s.resolution)
    integ = run.integrator(fields={"fg_color": cam}, composition=s.composition)
    problem = EditProblem(run, integ, ["fg_color.color"], ("composite", "bg"),
                          lambda out, color, mask: camouflage_loss(out["composite"][0], out["bg"][0]),
                          batch=s.batch_rays, pool=run.pixels_near_object(s.ray_dilation), seed=s.seed)
    log = run_optimisation(output, problem, Adam({"fg_color.color": s.lr}), "camouflage", progress)
    after = depth_and_errors(run, integ, views)
    output.write_views(integ)
    output.write_scene({**run.fields, "fg_color": cam}, composition=s.composition)
    ds = run.dataset
    gt = {}
    if ds.backgrounds is not None:
        gt = {f"composite_vs_gt_background_{when}": float(np.mean([
            psnr(np.clip(renders[v][2]["composite"][0], 0, 1), ds.backgrounds[v]) for v in views]))
            for when, renders in (("before", before), ("after", after))}
    output.finish({"task": "camouflage", "composition": s.composition, "steps": s.steps,
                   "psnr_to_background_before": float(np.mean([before[v][1] for v in views])),
                   "psnr_to_background_after": float(np.mean([after[v][1] for v in views])),
                   "max_depth_change": float(max(np.abs(before[v][0] - after[v][0]).max() for v in views)),
                   **gt}, log)
