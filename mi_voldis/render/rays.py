"""Render arbitrary ray batches through a ``voldis`` integrator, differentiably.

``mi.render`` renders whole sensors; fitting and the tasks instead draw random rays across all views.
:func:`render_rays` runs the same march (same sampler, quadrature and mixing) on given rays and is a
Dr.Jit custom operation: ``dr.backward`` on any loss of its outputs runs the path-replay adjoint
once and lands in the fields' ``density`` and ``color`` tensors.
"""
import drjit as dr
import mitsuba as mi

from . import layers as layer_io
from . import march


class _RenderRays(dr.CustomOp):
    def eval(self, tracked, plan, o, d, u, t_min, t_max):
        # ``tracked``: the packed grids that need gradients, only there to link the op into the AD graph
        rays = march.prepare_rays(plan, o, d, t_min, t_max)
        self.fwd = march.forward(plan, rays, u, True, keep_record=bool(tracked))
        self.sums = layer_io.raw_sums(plan, self.fwd.acc)
        out = layer_io.finalize(self.sums)
        out.update(self.fwd.stats)  # per-ray statistics, not differentiable
        iterations = out.pop("iterations")
        if plan.distortion_chains:
            out["distortion"] = {layer: march.distortion_value(self.fwd.acc[march.dist_name(c)])
                                 for layer, c in plan.distortion_chains.items()}
        dr.eval(out, iterations, self.fwd.acc)  # one kernel: loop outputs evaluated apart would run it again
        if tracked:
            self.fwd.order = march.adjoint_order(iterations)
        return out

    def backward(self):
        grad_out = self.grad_out()
        plan = self.fwd.plan
        raw = layer_io.finalize_adjoint(self.sums, {k: grad_out[k] for k in plan.layers})
        if plan.distortion_chains:
            raw["distortion"] = grad_out["distortion"]
        grads = march.backward(self.fwd, raw)
        self.set_grad_in("tracked", tuple(grads[id(f)] for f in plan.fields if grads[id(f)] is not None))

    def name(self):
        return "voldis.render_rays"


def render_rays(integrator, o, d, u, layers=("full", "bg"), samples=None, t_min=0.0, t_max=dr.inf, distortion=(),
                near_grad=0.0):
    """Layers of the scene along rays ``o + t d`` (world space, ``d`` unit length).

    ``u``: per-ray jitter in [0, 1) of the stratified samples; ``t_min``, ``t_max``: world-space
    limits (world-space scenes); ``layers``: any of ``composite``,
    ``full``, ``bg``, ``fg``, ``res``; ``samples``: per ray (default: the integrator's). Returns
    ``{layer: (rgb, alpha, depth)}`` (premultiplied ``mi.Color3f``, ``mi.Float``, ``mi.Float``),
    differentiable with respect to the fields' ``density`` and ``color`` tensors, plus
    ``"evaluated"``: the samples evaluated per ray (occupied cells, before early termination) and
    ``"fg_coverage"``: sum_i max(w_fg,i, 0) (see :func:`march.march`), neither differentiable; with
    ``distortion`` (layers among ``full``, ``bg``), ``"distortion"``: {layer: its per-ray distortion
    loss} (:mod:`mi_voldis.render.march`), differentiable. ``near_grad`` > 0: gradients of samples
    nearer the ray's origin than that world distance scaled by (d / near_grad)^2 (the march's docstring);
    the values are unchanged."""
    plan = integrator.plan(tuple(layers), samples, tuple(distortion), near_grad)
    tracked = tuple(f.packed for f in plan.fields if dr.grad_enabled(f.packed))
    return dr.custom(_RenderRays, tracked, plan, mi.Point3f(o), mi.Vector3f(d), mi.Float(u), t_min, t_max)
