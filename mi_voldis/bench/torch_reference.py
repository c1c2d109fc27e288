"""PyTorch CPU reference of the voldis ray march (one field, dense or in bricks), for side-by-side speed
benchmarks.

Written the usual DVGO/Plenoxels way: all B x N samples in one ``grid_sample`` call. The model is the
Dr.Jit renderer's ``full`` layer:

- raw grid of shape (1, 4, Z, Y, X) (channel 0 density, 1-3 RGB) over the box [lo, hi]; vertex
  (i, j, k) sits at lo + (i / (X-1), j / (Y-1), k / (Z-1)) (hi - lo) (``align_corners=True``); or the
  same lattice in bricks (:class:`TorchBrickField`: a brick table and the allocated bricks' vertex
  rows, :mod:`mi_voldis.field.bricks`), read corner by corner with index gathers;
- after trilinear interpolation, sigma = density_scale * softplus(raw_0) inside the box, 0 outside,
  and c = sigmoid(raw_1..3);
- a ray o + t d (d unit) samples its box interval [t0, t1] (clipped to t >= 0) at
  t_i = t0 + (i + u) dt, dt = (t1 - t0) / N, with one jitter u per ray, and delta_i = dt;
- alpha_i = 1 - exp(-sigma_i delta_i), T_i = exp(-sum_{j<i} sigma_j delta_j), w_i = T_i alpha_i,
  C = sum_i w_i c_i and A = sum_i w_i, without early termination (the Dr.Jit march stops once
  T < 1e-4, so the two agree to about 1e-4).
"""
import os

import numpy as np
import torch
import torch.nn.functional as F

from .rays import bench_rays


class TorchGridField:
    """Raw grid ``grid`` (1, 4, Z, Y, X) over the box [lo, hi] with the density scale."""

    def __init__(self, grid, lo, hi, density_scale=1.0):
        self.grid = grid
        self.lo = torch.as_tensor(lo, dtype=torch.float32)
        self.hi = torch.as_tensor(hi, dtype=torch.float32)
        self.density_scale = float(density_scale)

    @classmethod
    def from_numpy(cls, density, color, lo, hi, density_scale=1.0):
        """Field from raw grids in Mitsuba's layout: ``density`` (Z, Y, X[, 1]), ``color`` (Z, Y, X, 3)."""
        density = np.asarray(density, np.float32).reshape(np.shape(color)[:3] + (1,))
        packed = np.concatenate([density, np.asarray(color, np.float32)], axis=-1)
        grid = torch.from_numpy(np.ascontiguousarray(packed.transpose(3, 0, 1, 2)[None]))
        return cls(grid, lo, hi, density_scale)


class TorchBrickField:
    """A brick grid (:mod:`mi_voldis.field.bricks`): ``table`` (bz, by, bx) int64 slots, ``data`` (slots * B^3,
    4) raw values (the empty brick first), ``shape`` (X, Y, Z) vertices, over the box [lo, hi]."""

    def __init__(self, table, data, shape, brick, lo, hi, density_scale=1.0):
        self.table, self.grid, self.shape, self.brick = table, data, tuple(shape), brick
        self.lo = torch.as_tensor(lo, dtype=torch.float32)
        self.hi = torch.as_tensor(hi, dtype=torch.float32)
        self.density_scale = float(density_scale)

    @classmethod
    def from_numpy(cls, density, color, lo, hi, density_scale=1.0, brick=8, keep=None):
        """Field from raw grids in Mitsuba's layout (as :meth:`TorchGridField.from_numpy`) in bricks."""
        from ..field.bricks import from_dense
        density = np.asarray(density, np.float32).reshape(np.shape(color)[:3] + (1,))
        values = np.concatenate([density, np.asarray(color, np.float32)], axis=-1)
        layout, data = from_dense(values, brick, keep, width=4)
        return cls(torch.from_numpy(layout.table.astype(np.int64)), torch.from_numpy(data.reshape(-1, 4)),
                   layout.shape, brick, lo, hi, density_scale)

    def lookup(self, g):
        """Raw values [4, M] at points ``g`` [M, 3] in [-1, 1] (clamped), trilinear over the lattice."""
        res = torch.tensor(self.shape, dtype=torch.float32) - 1
        x = (g.clamp(-1.0, 1.0) + 1.0) * 0.5 * res
        i0 = torch.minimum(x.floor(), res - 1).long()
        f = x - i0
        b, m = self.brick, self.brick - 1
        out = 0.0
        for dz in (0, 1):
            for dy in (0, 1):
                for dx in (0, 1):
                    c = i0 + torch.tensor([dx, dy, dz])
                    slot = self.table[c[:, 2] // b, c[:, 1] // b, c[:, 0] // b]
                    v = slot * b ** 3 + ((c[:, 2] & m) * b + (c[:, 1] & m)) * b + (c[:, 0] & m)
                    w = (f[:, 0] if dx else 1 - f[:, 0]) * (f[:, 1] if dy else 1 - f[:, 1]) * \
                        (f[:, 2] if dz else 1 - f[:, 2])
                    out = out + w[:, None] * self.grid[v]
        return out.T


def box_interval(o, d, lo, hi):
    """Slab test of rays (o, d) [B, 3] against [lo, hi], clipped to t >= 0: (t0, t1), both 0 on a miss.
    Axes with d = 0 contribute everything or nothing, depending on whether o is inside that slab."""
    with torch.no_grad():
        ta, tb = (lo - o) / d, (hi - o) / d
        parallel = d == 0
        inside = (o >= lo) & (o <= hi)
        inf = torch.full_like(o, float("inf"))
        near = torch.where(parallel, torch.where(inside, -inf, inf), torch.minimum(ta, tb))
        far = torch.where(parallel, torch.where(inside, inf, -inf), torch.maximum(ta, tb))
        t0 = near.amax(dim=1).clamp(min=0.0)
        t1 = far.amin(dim=1)
        hit = t0 < t1
        return torch.where(hit, t0, 0.0), torch.where(hit, t1, 0.0)


def render(field, o, d, u, n_samples):
    """Colour [B, 3] and alpha [B] of rays ``o + t d`` (unit ``d``) with per-ray jitter ``u`` [B]."""
    t0, t1 = box_interval(o, d, field.lo, field.hi)
    dt = (t1 - t0) / n_samples
    t = t0[:, None] + (torch.arange(n_samples, dtype=o.dtype) + u[:, None]) * dt[:, None]  # [B, N]
    p = o[:, None, :] + t[..., None] * d[:, None, :]                                         # [B, N, 3]
    g = (p - field.lo) * (2.0 / (field.hi - field.lo)) - 1.0                                 # in [-1, 1]
    if isinstance(field, TorchBrickField):
        raw = field.lookup(g.reshape(-1, 3)).reshape(4, *g.shape[:2])                        # [4, B, N]
    else:
        raw = F.grid_sample(field.grid, g[None, None], mode="bilinear", padding_mode="border",
                            align_corners=True)[0, :, 0]                                     # [4, B, N]
    inside = (g.abs() <= 1.0).all(dim=-1)
    sigma = torch.where(inside, field.density_scale * F.softplus(raw[0]), 0.0)
    x = sigma * dt[:, None]                                                                  # sigma delta
    w = torch.exp(x - torch.cumsum(x, dim=1)) * -torch.expm1(-x)                             # T_i alpha_i
    rgb = (w * torch.sigmoid(raw[1:])).sum(dim=-1).T
    return rgb, w.sum(dim=1)


def torch_rays(kind, n, seed):
    """The Dr.Jit benchmark's rays (:func:`mi_voldis.bench.rays.bench_rays`, same draws) as tensors."""
    return tuple(torch.from_numpy(a) for a in bench_rays(kind, n, seed))


def random_field(resolution, seed=0, representation="dense"):
    """The Dr.Jit benchmark's ``full`` field (``throughput.make_integrator``): raw density
    normal(-1, 1), raw colour normal(0, 1), R^3 vertices over [-1, 1]^3, dense or in bricks."""
    rng = np.random.default_rng(seed)
    shape = (resolution,) * 3
    density, color = rng.normal(-1, 1, shape + (1,)), rng.normal(0, 1, shape + (3,))
    cls = TorchBrickField if representation == "bricks" else TorchGridField
    return cls.from_numpy(density, color, [-1.0] * 3, [1.0] * 3)


def step_functions(resolution, samples, batch, threads=None, rays="random", representation="dense"):
    """{"forward": f, "train": f} as in ``throughput.step_functions``: ``f(seed)`` runs one forward (no
    grad) or training step (forward + backward + Adam, lr 1e-2, MSE to the colour (0.5, 0.4, 0.3)) on
    fresh rays, drawing them included, and returns the samples (rays x samples per ray)."""
    torch.set_num_threads(threads or os.cpu_count())
    field = random_field(resolution, representation=representation)
    field.grid.requires_grad_(True)
    opt = torch.optim.Adam([field.grid], lr=1e-2)
    target = torch.tensor([0.5, 0.4, 0.3])

    def forward(seed):
        with torch.no_grad():
            render(field, *torch_rays(rays, batch, seed), samples)
        return batch * samples

    def train(seed):
        opt.zero_grad(set_to_none=True)
        rgb, _ = render(field, *torch_rays(rays, batch, seed), samples)
        torch.mean(torch.square(rgb - target)).backward()
        opt.step()
        return batch * samples
    return {"forward": forward, "train": train}


def measure(resolution, samples, batch, steps=5, warmup=2, threads=None, rays="random", representation="dense"):
    """Median seconds per forward and per training step, and million samples per second of each."""
    from .throughput import interleaved
    fns = step_functions(resolution, samples, batch, threads, rays, representation)
    return interleaved({"torch": fns}, steps, {"torch": warmup}, rounds=1)["torch"]
