"""Text-guided restyling of the foreground with CLIP (paper Sec. 3.3).

As camouflage, a foreground colour field over the object's box replaces c_fg (geometry and depth stay
as they are) and only its colours are optimised, here with :func:`mi_voldis.losses.semantic_loss`: CLIP
similarity of the mask-composited view to the prompt, similarity to the background view, and L2 to the
original outside the mask, on 128 x 128 ray grids from views rendered at 252 x 189.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import pixel_rays
from ..device import from_numpy
from ..losses import semantic_loss
from ..optim.adam import Adam
from ..render.rays import render_rays
from .base import EditProblem, run_optimisation
from .camouflage import colour_field


def run(run, output, progress=True):
    from .clip import ClipGuide
    s = output.settings
    guide = ClipGuide(s.clip_model, s.prompt)
    cam = colour_field(run, s.resolution)
    integ = run.integrator(fields={"fg_color": cam})
    problem = ClipProblem(run, integ, guide, s.bg_weight, s.l2_weight, s.seed)
    views = list(run.dataset.test)
    sim_before = problem.similarity(views)
    log = run_optimisation(output, problem, Adam({"fg_color.color": s.lr}), "semantic", progress)
    sim_after = problem.similarity(views)
    output.write_views(integ)
    output.write_scene({**run.fields, "fg_color": cam})
    output.finish({"task": "semantic", "prompt": s.prompt, "steps": s.steps,
                   "clip_similarity_before": sim_before, "clip_similarity_after": sim_after}, log)


class ClipProblem(EditProblem):
    """The paper's text-guided loss on 128 x 128 ray grids over views rendered at 252 x 189 (a crop around the
    object, at a random training view each step)."""
    WIDTH, HEIGHT, GRID = 252, 189, 128

    def __init__(self, run, integrator, guide, bg_weight, l2_weight, seed):
        super().__init__(run, integrator, ["fg_color.color"], ("composite", "full", "bg"), None, seed=seed)
        self.guide, self.bg_weight, self.l2_weight = guide, bg_weight, l2_weight

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
        loss = semantic_loss(self.guide, images["composite"], images["bg"], images["full"], mask, self.bg_weight,
                             self.l2_weight)
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
