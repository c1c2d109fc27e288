"""Non-negative inpainting: a residual volume that only adds light (see-through AR displays; paper Sec. 3.2).

The residual is a radiance field rendered with its own weights and added to the full render:
x^full + x^res, with x^res = sum_i w^res_i c^res_i >= 0 because its weights (softplus density,
standard quadrature) and colours (sigmoid) are non-negative by construction, not clipped after the
fact. It is optimised, over a grid around the object, with :func:`mi_voldis.losses.nonneg_loss`.
Where the background is darker than the scene no added light can reach it, and the error there
cannot drop: the metrics report the error split into pixels where x^bg >= x^full and where it is not.
"""
import numpy as np

from ..losses import nonneg_loss
from ..metrics import psnr
from ..optim.adam import Adam
from ..render.views import render_camera
from .base import EditProblem, residual_field, run_optimisation


def run(run, output, progress=True):
    s = output.settings
    residual = residual_field(run, s.resolution, s.init_alpha, s.init_color)
    integ = run.integrator(fields={"residual": residual}, mode="full")
    problem = EditProblem(run, integ, ["residual.density", "residual.color"], ("full", "bg", "res"),
                          lambda out, color, mask: nonneg_loss(out["full"][0], out["res"][0], out["bg"][0]),
                          batch=s.batch_rays, pool=run.pixels_near_object(s.ray_dilation), seed=s.seed)
    log = run_optimisation(output, problem, Adam({"residual.density": s.lr_density, "residual.color": s.lr_color}),
                           "nonneg", progress)
    rows = []
    for v in run.dataset.test:
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
    output.write_scene({**run.fields, "residual": residual}, mode="full")
    output.finish({"task": "nonneg", "steps": s.steps,
                   **{k: float(np.nanmean([row[k] for row in rows])) for k in rows[0]},
                   "min_residual": float(min(row["min_residual"] for row in rows)), "per_view": rows}, log)
