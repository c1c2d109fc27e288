"""Occupancy grid: which cells of scene space may hold density, so the march can skip the others.

A cell is occupied when some field lookup of the plan (its box moved by its transform) has a grid
vertex in the cell or a neighbouring cell whose density exceeds a threshold. Trilinear interpolation
never exceeds its corner values, and the one-cell dilation covers voxels that straddle cell borders,
so a skipped sample has density below the threshold in every field: skipping it changes no chain's
optical depth by more than threshold x sample spacing. All fields share the grid, so a skipped
sample is skipped in every field and the samples stay aligned.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..field.activations import inverse_softplus
from ..field.grid import dilate_cells
from ..transforms import apply_point


class Occupancy:
    """Boolean grid of shape (Z, Y, X) over the scene-space box [lo, hi]."""

    def __init__(self, lo, hi, cells, reach=0.0):
        self.reach = reach  # how far density reaches beyond a marked vertex: the largest voxel of the fields
        self.lo, self.hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        self.cells = np.asarray(cells, bool)
        self.shape = self.cells.shape[::-1]  # (X, Y, Z)
        self.data = mi.Float(self.cells.ravel().astype(np.float32))

    def bounds(self):
        """World -> unit-cube matrix of the axis-aligned box around the occupied cells (None when
        nothing is occupied): rays are only sampled inside it."""
        z, y, x = np.nonzero(self.cells)
        if len(x) == 0:
            return None
        cell = (self.hi - self.lo) / np.array(self.shape)
        lo = self.lo + np.array([x.min(), y.min(), z.min()]) * cell
        hi = self.lo + (np.array([x.max(), y.max(), z.max()]) + 1) * cell
        m = np.diag([*(1.0 / (hi - lo)), 1.0])
        m[:3, 3] = -lo / (hi - lo)
        return m

    @property
    def cell_size(self):
        """Smallest edge of a cell (scene units)."""
        return float(np.min((self.hi - self.lo) / np.array(self.shape)))

    @property
    def fraction(self):
        """Occupied fraction of the cells."""
        return float(self.cells.mean())

    def _cells(self, p):
        """Scene-space points ``p`` in cell units (0 at ``lo``, one per cell) and the scale that maps to them."""
        scale = mi.Vector3f(*[float(s / e) for s, e in zip(self.shape, self.hi - self.lo)])
        return (p - mi.Vector3f(*self.lo.tolist())) * scale, scale

    def lookup(self, p):
        """True where the scene-space points ``p`` fall in an occupied cell."""
        u, _ = self._cells(p)
        inside = dr.all((u >= 0.0) & (u < mi.Vector3f(*self.shape)))
        i = mi.Vector3u(dr.clip(mi.Vector3i(u), 0, mi.Vector3i(*[s - 1 for s in self.shape])))
        idx = (i.z * self.shape[1] + i.y) * self.shape[0] + i.x
        return inside & (dr.gather(mi.Float, self.data, idx, inside) > 0.0)

    def exit_distance(self, p, d):
        """The t >= 0 at which p + t d leaves the cell that holds the scene-space point ``p`` (``d``: a
        scene-space direction, not necessarily unit): per axis (face - u) / du in cell units, the
        nearest face ahead (infinite along an axis ``d`` does not move in)."""
        u, scale = self._cells(p)
        du, c = d * scale, dr.floor(u)
        ahead = [dr.select(du[a] > 0.0, (c[a] + 1.0 - u[a]) / du[a],
                           dr.select(du[a] < 0.0, (c[a] - u[a]) / du[a], dr.inf)) for a in range(3)]
        return dr.maximum(dr.minimum(dr.minimum(ahead[0], ahead[1]), ahead[2]), 0.0)

    @staticmethod
    def build(lookups, space, resolution, sigma_threshold, boxes_lo, boxes_hi, extra=None):
        """Occupancy of the density-carrying ``lookups`` over the box [boxes_lo, boxes_hi] with
        ``resolution`` cells along its longest side. ``extra``: optional (N, 3) scene-space points that
        must be occupied (e.g. a region a field is about to grow into). Cells are marked on the device;
        only the cell grid comes back to the host."""
        lo, hi = np.asarray(boxes_lo, np.float64), np.asarray(boxes_hi, np.float64)
        size = hi - lo
        shape = np.maximum(1, np.ceil(resolution * size / size.max()).astype(int))  # (X, Y, Z)
        marks = dr.zeros(mi.Float, int(np.prod(shape)))
        reach = 0.0
        for lk in lookups:
            raw_threshold = float(inverse_softplus(sigma_threshold / lk.field.density_scale))
            local = lk.field.density_points(raw_threshold)
            if dr.width(local) == 0:
                continue
            _mark(marks, lo, size, shape, local_to_scene(lk, space, local))
            m = np.linalg.inv(lk.to_local)  # the lookup's voxel in scene units (before any warp)
            reach = max(reach, float(np.max(np.linalg.norm(m[:3, :3], axis=0) / (np.array(lk.field.shape) - 1))))
        if extra is not None and len(extra):
            _mark(marks, lo, size, shape, mi.Point3f(*np.asarray(extra, np.float32).T))
        cells = np.array(marks).reshape(shape[::-1]) > 0
        return Occupancy(lo, hi, dilate_cells(cells), reach)


def local_to_scene(lk, space, local):
    """Scene-space positions (Dr.Jit Point3f) of unit-cube points of a lookup's field (inverse of its
    lookup map)."""
    to_scene = np.linalg.inv(lk.to_local)
    if lk.warp is None:
        return apply_point(to_scene, local)
    world = space.to_world(apply_point(to_scene, local))  # field box in scene space, then the world transform
    return space.from_world(apply_point(np.linalg.inv(lk.warp), world))


def local_to_scene_np(lk, space, local):
    """NumPy version of :func:`local_to_scene` for (n, 3) points."""
    to_scene = np.linalg.inv(lk.to_local)
    p = np.asarray(local, np.float64) @ to_scene[:3, :3].T + to_scene[:3, 3]
    if lk.warp is None:
        return p
    inv = np.linalg.inv(lk.warp)
    return space.from_world_np(space.to_world_np(p) @ inv[:3, :3].T + inv[:3, 3])


def _mark(marks, lo, size, shape, points):
    """Set the cells (flat Float, 1 = marked) holding the scene-space ``points``."""
    u = (points - mi.Vector3f(*lo.tolist())) * mi.Vector3f(*(shape / size).tolist())
    inside = dr.all((u >= 0.0) & (u < mi.Vector3f(*shape.tolist()))) & dr.all(dr.isfinite(points))
    i = mi.Vector3u(mi.Vector3i(dr.select(inside, u, 0.0)))
    dr.scatter(marks, 1.0, (i.z * int(shape[1]) + i.y) * int(shape[0]) + i.x, inside)
