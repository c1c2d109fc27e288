"""The fields of a fit: what it reads (:class:`FitInputs`), how its fields start, shrink to the space
rays end in, and the integrator that renders them. Free functions of the inputs and a
:class:`~mi_voldis.fit.state.FitState`."""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..data.types import Dataset
from ..field_state import FieldState, density_raw_for_alpha, init_state, resample, voxel_size
from ..raybank import RayBank
from ..render.rays import render_rays
from ..scene import build_integrator, integrator_properties
from ..space import SceneSpace
from .config import FitConfig


@dataclass(frozen=True)
class FitInputs:
    """What a fit reads and never changes: the dataset, the settings, the scene space, the training
    rays, the checkpoint file and whether to show progress."""
    ds: Dataset
    cfg: FitConfig
    space: SceneSpace
    bank: RayBank
    checkpoint: str
    progress: bool = True

    @classmethod
    def of(cls, dataset, cfg, checkpoint, progress=True):
        return cls(dataset, cfg, SceneSpace.from_box(dataset.box), RayBank(dataset, dataset.train), checkpoint,
                   progress)


def cell_size(lo, hi, resolution):
    """Edge of a cubic voxel of a grid with ``resolution`` vertices along the longest side of [lo, hi]."""
    return float((hi - lo).max() / (resolution - 1))


def init_fields(inputs, state, roles, sh_degree):
    """Fields of ``roles`` at the schedule's first resolution, every voxel equally faintly opaque
    (``density_init_alpha`` per sample step), raw densities per voxel of the finest resolution."""
    cfg = inputs.cfg
    res = cfg.resolution_schedule[0][1]
    step = cell_size(state.lo, state.hi, res) * cfg.step_voxels
    scale = 1.0 / cell_size(state.lo, state.hi, cfg.resolution_schedule[-1][1])
    raw = density_raw_for_alpha(cfg.density_init_alpha, step, scale)
    for r in roles:
        state.fields[r] = init_state(state.lo, state.hi, res, sh_degree, raw, scale)


def occupancy_sigma(cfg, state):
    """Density (per scene unit) of a voxel of opacity ``occupancy_alpha`` at the current grid."""
    return -np.log1p(-cfg.occupancy_alpha) / voxel_size(state.fields["full"])


def sample_step(cfg, state):
    """Sample spacing along rays (scene units): ``step_voxels`` of the current grid's voxels."""
    return cfg.step_voxels * voxel_size(state.fields["full"])


def fit_integrator(inputs, state):
    """The ``voldis`` integrator over the current fields (no occupancy: fitting updates it itself)."""
    full = state.fields["full"]
    bg = state.fields.get("bg")
    if bg is None:  # the full phase of "refit": an empty stand-in background over the same box
        bg = FieldState(dr.full(mi.TensorXf, -30.0, (2, 2, 2, 1)), dr.zeros(mi.TensorXf, (2, 2, 2, 3)), full.to_world)
    props = integrator_properties(inputs.space, samples=inputs.cfg.max_samples,
                                  step_size=sample_step(inputs.cfg, state))
    return build_integrator({"full": full.plugin(), "bg": bg.plugin()}, props)


def tighten(inputs, state, integrator):
    """Shrink the box to the space the training rays end in; skip empty space from now on."""
    box = seen_box(inputs, state, integrator)
    if box is not None:
        state.lo, state.hi = box
        empty = density_raw_for_alpha(1e-6, 1.0, state.fields["full"].density_scale)
        for r in list(state.fields):
            state.fields[r] = resample(state.fields[r], max(state.fields[r].shape), state.lo, state.hi, empty)
    state.occupancy_on = inputs.cfg.occupancy_resolution > 0


def seen_box(inputs, state, integrator, rays=1 << 16):
    """Scene-space bounds of where random training rays end (alpha > 0.5, at their expected
    depth), grown by ``tighten_margin`` of the size and two voxels; None if no ray ends."""
    cfg, bank = inputs.cfg, inputs.bank
    rng = np.random.default_rng([cfg.seed, 99])
    idx = rng.integers(0, bank.pixels, rays).astype(np.uint32)
    o, d, _, _ = bank.rays(idx, np.full((rays, 2), 0.5, np.float32))
    with dr.suspend_grad():
        out = render_rays(integrator, o, d, dr.full(mi.Float, 0.5, rays), ("full",))
    alpha, depth = np.array(out["full"][1]), np.array(out["full"][2])
    keep = alpha > 0.5
    if not keep.any():
        return None
    pts = np.array(o).T[keep] + depth[keep, None] * np.array(d).T[keep]
    pts = inputs.space.from_world_np(pts)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = cfg.tighten_margin * (hi - lo) + 2 * voxel_size(state.fields["full"])
    return np.maximum(lo - pad, state.lo), np.minimum(hi + pad, state.hi)
