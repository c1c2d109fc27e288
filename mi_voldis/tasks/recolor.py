"""Colour edits of the foreground: camouflage and text-guided (CLIP) restyling.

Both add a foreground colour field c_cam over the object's region (a grid over the box where the full
and background fields differ, not the whole scene) which replaces c_fg in the composite; its density
is unused, so the foreground weights w'_fg = w_fg, and with them every depth, are unchanged by
construction. Only that colour grid is optimised.

* camouflage: L = sum_i ||x^c_i - x^bg_i||^2, the composite against the background render of the
  same rays (the object should vanish into what is behind it while keeping its shape).
* semantic: paper Eqs. 2-4 with CLIP: text similarity of the mask-composited view, similarity to the
  background view, and L2 to the original render outside the mask; 128 x 128 ray grids from views
  rendered at 252 x 189.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..data.cameras import pixel_rays
from ..device import from_numpy
from ..metrics import psnr
from ..optim.adam import Adam
from ..render.rays import render_rays
from ..render.views import render_camera
from .base import EditProblem, edit_field, pixels_near_object, run_optimisation

RESOLUTION = 48      # colour-grid vertices along the object box's longest side
LR = 0.05            # Adam learning rate on raw colour


def colour_field(run, resolution=RESOLUTION):
    lo, hi = run.foreground_box()
    return mi.load_dict(edit_field(lo, hi, resolution))


def depth_and_errors(run, integrator, views):
    """Composite depth and the composite's error to the background render, per view."""
    out = {}
    for v in views:
        r = render_camera(integrator, run.dataset.cameras[v], ("composite", "bg"))
        out[v] = (r["composite"][2], psnr(np.clip(r["composite"][0], 0, 1), np.clip(r["bg"][0], 0, 1)), r)
    return out


def camouflage(run, output, options):
    rule = options.get("composition") or "paper"
    steps = int(options.get("steps") or 300)
    views = list(run.dataset.test)
    before = depth_and_errors(run, run.integrator(composition=rule), views)
    cam = colour_field(run, int(options.get("resolution") or RESOLUTION))
    integ = run.integrator(fields={"fg_color": cam}, composition=rule)

    def loss_fn(out, color, mask):
        return dr.mean(dr.squared_norm(out["composite"][0] - dr.detach(out["bg"][0]))) / 3.0
    problem = EditProblem(run, integ, ["fg_color.color"], ("composite", "bg"), loss_fn,
                          pool=pixels_near_object(run), seed=int(options.get("seed") or 0))
    log = run_optimisation(output, problem, Adam({"fg_color.color": LR}), steps, "camouflage",
                           options)
    after = depth_and_errors(run, integ, views)
    output.write_views(integ)
    output.write_scene({**run.fields, "fg_color": cam}, {"composition": rule})
    ds = run.dataset
    gt = {}
    if ds.backgrounds is not None:
        gt = {"composite_vs_gt_background_before": float(np.mean([psnr(np.clip(before[v][2]["composite"][0], 0, 1),
                                                                         ds.backgrounds[v]) for v in views])),
              "composite_vs_gt_background_after": float(np.mean([psnr(np.clip(after[v][2]["composite"][0], 0, 1),
                                                                        ds.backgrounds[v]) for v in views]))}
    metrics = {"task": "camouflage", "composition": rule, "steps": steps,
               "psnr_to_background_before": float(np.mean([before[v][1] for v in views])),
               "psnr_to_background_after": float(np.mean([after[v][1] for v in views])),
               "max_depth_change": float(max(np.abs(before[v][0] - after[v][0]).max() for v in views)),
               **gt}
    return output.finish(metrics, log)


def semantic(run, output, options):
    from .clip import ClipGuide
    prompt = options.get("prompt")
    model = options.get("clip_model")
    if not prompt or not model:
        raise ValueError("the semantic task needs --prompt TEXT and --clip-model PATH (a local CLIP folder)")
    guide = ClipGuide(model, prompt)
    steps = int(options.get("steps") or 100)
    cam = colour_field(run, int(options.get("resolution") or RESOLUTION))
    integ = run.integrator(fields={"fg_color": cam})
    problem = ClipProblem(run, integ, guide, float(options.get("l2_weight") or 10.0), int(options.get("seed") or 0))
    views = list(run.dataset.test)
    sim_before = problem.similarity(views)
    log = run_optimisation(output, problem, Adam({"fg_color.color": LR}), steps, "semantic",
                           options)
    sim_after = problem.similarity(views)
    output.write_views(integ)
    output.write_scene({**run.fields, "fg_color": cam}, {"composition": integ.composition})
    return output.finish({"task": "semantic", "prompt": prompt, "steps": steps,
                          "clip_similarity_before": sim_before, "clip_similarity_after": sim_after}, log)


class ClipProblem(EditProblem):
    """Paper Eqs. 2-4 on 128 x 128 ray grids over views rendered at 252 x 189 (a crop around the
    object, at a random training view each step)."""
    WIDTH, HEIGHT, GRID = 252, 189, 128

    def __init__(self, run, integrator, guide, l2_weight, seed):
        super().__init__(run, integrator, ["fg_color.color"], ("composite", "full", "bg"), None, seed=seed)
        self.guide, self.l2_weight = guide, l2_weight

    def grid(self, view, rng):
        """World rays of a 128 x 128 grid over a crop of the 252 x 189 view around the object, and the
        object mask there."""
        ds = self.run.dataset
        cam = ds.cameras[view]
        sx, sy = self.WIDTH / cam.width, self.HEIGHT / cam.height
        if ds.masks is not None and ds.masks[view].any():
            ys, xs = np.nonzero(ds.masks[view])
            cx, cy = 0.5 * (xs.min() + xs.max() + 1) * sx, 0.5 * (ys.min() + ys.max() + 1) * sy
        else:
            cx, cy = self.WIDTH / 2, self.HEIGHT / 2
        size = self.GRID
        x0 = np.clip(cx - size / 2 + rng.uniform(-8, 8), 0, self.WIDTH - size)
        y0 = np.clip(cy - size / 2 + rng.uniform(-8, 8), 0, self.HEIGHT - size)
        gy, gx = np.mgrid[0:size, 0:size] + 0.5
        px, py = (x0 + gx) / sx, (y0 + gy) / sy  # in the dataset's pixel units
        o, d = pixel_rays(cam, px.ravel(), py.ravel())
        if ds.masks is not None:
            mask = ds.masks[view][np.clip(py.astype(int), 0, cam.height - 1), np.clip(px.astype(int), 0, cam.width - 1)]
        else:
            mask = np.ones((size, size), bool)
        return from_numpy(mi.Point3f, o), from_numpy(mi.Vector3f, d), mask.astype(np.float32)

    def render(self, view, rng):
        o, d, mask = self.grid(view, rng)
        out = render_rays(self.integrator, o, d, dr.full(mi.Float, 0.5, dr.width(o)), self.layers)
        shape = (self.GRID, self.GRID, 3)
        images = {k: mi.TensorXf(dr.ravel(out[k][0]), shape) for k in ("composite", "full", "bg")}
        return images, mi.TensorXf(mask.ravel(), (self.GRID, self.GRID, 1)), out

    def loss(self, step):
        rng = np.random.default_rng([self.seed, 11, step])
        view = int(rng.choice(self.run.dataset.train))
        images, mask, out = self.render(view, rng)
        edited = images["composite"]
        clip_loss = self.guide.loss(edited, dr.detach(images["bg"]), mask)
        outside = dr.mean(dr.square((1.0 - mask) * (edited - dr.detach(images["full"]))).array)  # Eq. 4
        loss = clip_loss + self.l2_weight * outside
        return loss, {"samples": float(dr.sum(out["evaluated"])[0])}

    def similarity(self, views):
        """Mean CLIP similarity to the prompt of the 128 x 128 mask-composited grids of ``views``."""
        values = []
        for v in views:
            images, mask, _ = self.render(v, np.random.default_rng(0))
            m = np.array(mask)
            img = m * np.clip(np.array(images["composite"]), 0, 1) + (1 - m) * np.clip(np.array(images["bg"]), 0, 1)
            values.append(self.guide.similarity(img))
        return float(np.mean(values))
