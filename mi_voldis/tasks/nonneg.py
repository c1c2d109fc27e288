"""Non-negative inpainting: a residual volume that only adds light (see-through AR displays).

The residual is a radiance field rendered with its own weights and added to the full render:
x^full + x^res, with x^res = sum_i w^res_i c^res_i >= 0 because its weights (softplus density,
standard quadrature) and colours (sigmoid) are non-negative by construction, not clipped after the
fact. It is optimised, over a grid around the object, with L = sum_i ||x^full_i + x^res_i - x^bg_i||^2.
Where the background is darker than the scene no added light can reach it, and the error there
cannot drop: the metrics report the error split into pixels where x^bg >= x^full and where it is not.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..fit import grids
from ..metrics import psnr
from ..optim.adam import Adam
from ..render.views import render_camera
from .base import EditProblem, edit_field, pixels_near_object, run_optimisation

RESOLUTION = 48
LR = 0.05


def run(run, output, options):
    lo, hi = run.foreground_box()
    res = int(options.get("resolution") or RESOLUTION)
    full = run.fields["full"]
    voxel = float(np.max((hi - lo) / (res - 1)))
    raw = grids.density_raw_for_alpha(1e-3, 0.5 * voxel, full.density_scale)
    residual = mi.load_dict(edit_field(lo, hi, res, density_raw=raw, color_raw=-2.0,
                                       density_scale=full.density_scale))
    integ = run.integrator(fields={"residual": residual}, mode="full")
    steps = int(options.get("steps") or 300)

    def loss_fn(out, color, mask):
        added = out["full"][0] + out["res"][0]
        return dr.mean(dr.squared_norm(added - dr.detach(out["bg"][0]))) / 3.0
    problem = EditProblem(run, integ, ["residual.density", "residual.color"], ("full", "bg", "res"), loss_fn,
                          pool=pixels_near_object(run), seed=int(options.get("seed") or 0))
    log = run_optimisation(output, problem, Adam({"residual.density": 0.1, "residual.color": LR}), steps,
                           "nonneg", options)
    views = list(run.dataset.test)
    rows = []
    for v in views:
        r = render_camera(integ, run.dataset.cameras[v], ("full", "bg", "res"))
        full_img, bg_img, res_img = (np.clip(r[k][0], 0, None) for k in ("full", "bg", "res"))
        brighter = (bg_img >= full_img).all(axis=-1)
        rows.append({"min_residual": float(r["res"][0].min()),
                     "psnr_before": psnr(full_img, bg_img), "psnr_after": psnr(full_img + res_img, bg_img),
                     "psnr_after_where_bg_brighter": psnr(full_img + res_img, bg_img, brighter),
                     "psnr_after_where_bg_darker": psnr(full_img + res_img, bg_img, ~brighter),
                     "psnr_before_where_bg_darker": psnr(full_img, bg_img, ~brighter),
                     "fraction_bg_darker": float((~brighter).mean())})
    output.write_views(integ, main="full", extra=("res",))
    output.write_scene({**run.fields, "residual": residual}, {"mode": "full"})
    metrics = {"task": "nonneg", "steps": steps,
               **{k: float(np.nanmean([row[k] for row in rows])) for k in rows[0]},
               "min_residual": float(min(row["min_residual"] for row in rows)), "per_view": rows}
    return output.finish(metrics, log)
