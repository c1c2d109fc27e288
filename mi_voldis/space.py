"""Scene space: where rays are sampled and fields live: world space, NDC, or a contracted space.

*World* space is the identity. *NDC* follows NeRF's forward-facing set-up: with a reference camera
(Mitsuba frame, +z forward), near plane n and scales (s_x, s_y) = (2 f / W, 2 f / H), a camera-frame
point (x, y, z) maps to

    (x', y', z') = (s_x x / z, s_y y / z, 1 - 2 n / z),

which sends the frustum from the near plane to infinity into z' in [-1, 1) and keeps straight lines
straight. A ray, first moved to start on the near plane, becomes o' + t' d' with t' in [0, 1) for
z in [n, inf): samples uniform in t' are uniform in disparity. Quadrature then uses NDC lengths
(delta = dt' |d'|, as NeRF does), so densities are per NDC unit; depths are reported in world units.
Every field is evaluated at the same scene-space points, so the warp keeps samples aligned.

*Contracted* space (Mip-NeRF 360's scene contraction with the L-infinity norm, as grids want it)
covers all of space, near and far, in every direction: a world point x is first normalised,
x_n = M^-1 x (``to_world`` M: a rotation, a uniform scale R and a translation c, so that the inner
region ||x_n||_inf <= 1 is a cube of half-size R around c), then

    contract(x_n) = x_n                                     if m = ||x_n||_inf <= 1,
                    ((1 + b) - b / m) x_n / m               otherwise,

which maps the world into the cube [-(1 + b), 1 + b]^3: linear inside, uniform in disparity 1 / m
outside, infinity on its surface (``shell`` b: the outer region's share). Rays are curves there, so
the march steps along the world ray with steps of constant scene-space length
(:meth:`SceneSpace.step_length`); densities are per scene unit, as in NDC.

A leaf module: datasets describe their space with a :class:`SceneBox`, rendering works in a
:class:`SceneSpace`, and :meth:`SceneSpace.integrator_properties` is the one conversion of a space
into ``voldis`` integrator properties (for plugin dicts and scene files alike).
"""
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from .transforms import apply_point, apply_vector, to_scalar_transform

NDC_T_MAX = 1.0 - 1e-6  # t' = 1 is at infinity


class SceneSpace:
    """``kind`` 'world' (identity), 'ndc' (``to_world``: reference camera frame -> world; ``near``,
    ``scale``) or 'contract' (``to_world``: normalised -> world; ``shell``: b)."""

    def __init__(self, kind="world", to_world=None, near=None, scale=None, shell=1.0):
        if kind not in ("world", "ndc", "contract"):
            raise ValueError(f"scene space must be 'world', 'ndc' or 'contract', got '{kind}'")
        self.kind = kind
        if kind == "contract":
            if to_world is None:
                raise ValueError("contracted space needs a normalising transform")
            self.to_world_m = np.asarray(to_world, np.float64)
            self.from_world_m = np.linalg.inv(self.to_world_m)
            if not shell > 0:
                raise ValueError(f"contracted space needs a shell width > 0, got {shell}")
            self.shell = float(shell)
        if kind == "ndc":
            if to_world is None or near is None or scale is None:
                raise ValueError("NDC space needs a reference frame, a near plane and two scales")
            if near <= 0 or min(scale) <= 0:
                raise ValueError(f"NDC space needs near > 0 and positive scales, got {near}, {scale}")
            self.to_world_m = np.asarray(to_world, np.float64)
            self.from_world_m = np.linalg.inv(self.to_world_m)
            self.near = float(near)
            self.scale = (float(scale[0]), float(scale[1]))

    @property
    def is_world(self):
        return self.kind == "world"

    @property
    def is_curved(self):
        """Rays are curves in this space (contracted): the march steps along world rays."""
        return self.kind == "contract"

    @property
    def extent(self):
        """Half-size of the cube the contracted space fills (1 + b)."""
        return 1.0 + self.shell

    # -------------------------------------------------------------------------- contraction
    def normalize(self, p):
        """x_n = M^-1 p of world points (contracted space)."""
        return apply_point(self.from_world_m, p)

    def contract(self, x):
        """Contraction of normalised points (module docstring), Dr.Jit."""
        m = dr.maximum(dr.max(dr.abs(x)), 1.0)
        return x * (((1.0 + self.shell) - self.shell / m) / m)

    def uncontract(self, p):
        """Inverse of :meth:`contract` for points of the open cube (|p|_inf < 1 + b)."""
        mc = dr.maximum(dr.max(dr.abs(p)), 1.0)
        m = self.shell / dr.maximum((1.0 + self.shell) - mc, 1e-7)
        return p * (m / mc)

    def step_length(self, x, d):
        """Scene-space length per unit of world length, ||J_contract(x) d||, at normalised points ``x``
        along normalised directions ``d`` (both Dr.Jit): d/dt contract(x + t d) at t = 0."""
        ax = dr.abs(x)
        m = dr.max(ax)
        outside = m > 1.0
        m = dr.maximum(m, 1.0)
        b = self.shell
        f = ((1.0 + b) - b / m) / m                           # contract(x) = f(m) x
        df = (2.0 * b / m - (1.0 + b)) / (m * m)              # f'(m)
        # dm/dt: the derivative of the largest |x_a| (the axis it is attained on)
        dm = dr.select((ax.x >= ax.y) & (ax.x >= ax.z), dr.sign(x.x) * d.x,
                       dr.select(ax.y >= ax.z, dr.sign(x.y) * d.y, dr.sign(x.z) * d.z))
        jd = f * d + x * (df * dm)
        return dr.select(outside, dr.norm(jd), dr.norm(d))

    def ray(self, o, d):
        """Scene-space ray (o', d') and the valid parameter range [0, t'_max] of a world ray."""
        if self.is_world:
            return o, d, dr.inf
        oc, dc = apply_point(self.from_world_m, o), apply_vector(self.from_world_m, d)
        oc = oc + dc * ((self.near - oc.z) / dc.z)  # start on the near plane, as NeRF does
        sx, sy = self.scale
        ox, oy = oc.x / oc.z, oc.y / oc.z
        o_ndc = mi.Point3f(sx * ox, sy * oy, 1.0 - 2.0 * self.near / oc.z)
        d_ndc = mi.Vector3f(sx * (dc.x / dc.z - ox), sy * (dc.y / dc.z - oy), 2.0 * self.near / oc.z)
        forward = dc.z > 0
        return (dr.select(forward, o_ndc, 0.0), dr.select(forward, d_ndc, 0.0),
                dr.select(forward, NDC_T_MAX, 0.0))

    def to_world(self, p):
        if self.is_world:
            return p
        if self.is_curved:
            return apply_point(self.to_world_m, self.uncontract(p))
        z = 2.0 * self.near / (1.0 - p.z)
        return apply_point(self.to_world_m, mi.Point3f(p.x * z / self.scale[0], p.y * z / self.scale[1], z))

    def from_world(self, p):
        if self.is_world:
            return p
        if self.is_curved:
            return self.contract(self.normalize(p))
        pc = apply_point(self.from_world_m, p)
        return mi.Point3f(self.scale[0] * pc.x / pc.z, self.scale[1] * pc.y / pc.z, 1.0 - 2.0 * self.near / pc.z)

    def scene_depth(self, o, d, t):
        """The depth of the world point o + t d seen from the world ray origin ``o`` (unit direction ``d``),
        measured in scene space where the space is contracted: the scene-space distance
        ||contract(o + t d) - contract(o)|| (bounded by the cube, so depths far out differ little); in a
        straight space (world, NDC) the world depth ``t`` itself (Dr.Jit, differentiable in ``t``)."""
        if not self.is_curved:
            return t
        step = self.from_world(o + t * d) - self.from_world(o)
        return dr.sqrt(dr.squared_norm(step) + 1e-12)

    # ----------------------------------------------------------------- NumPy versions (set-up)
    def from_world_np(self, p):
        """NumPy (n, 3) version of :meth:`from_world`."""
        p = np.asarray(p, np.float64)
        if self.is_world:
            return p
        pc = p @ self.from_world_m[:3, :3].T + self.from_world_m[:3, 3]
        if self.is_curved:
            m = np.maximum(np.abs(pc).max(axis=-1, keepdims=True), 1.0)
            return pc * (((1.0 + self.shell) - self.shell / m) / m)
        z = pc[:, 2]
        return np.stack([self.scale[0] * pc[:, 0] / z, self.scale[1] * pc[:, 1] / z, 1 - 2 * self.near / z], -1)

    def to_world_np(self, p):
        p = np.asarray(p, np.float64)
        if self.is_world:
            return p
        if self.is_curved:
            mc = np.maximum(np.abs(p).max(axis=-1, keepdims=True), 1.0)
            with np.errstate(divide="ignore"):
                m = self.shell / np.maximum((1.0 + self.shell) - mc, 1e-12)
            x = p * (m / mc)
            return x @ self.to_world_m[:3, :3].T + self.to_world_m[:3, 3]
        z = 2 * self.near / (1 - p[:, 2])
        pc = np.stack([p[:, 0] * z / self.scale[0], p[:, 1] * z / self.scale[1], z], -1)
        return pc @ self.to_world_m[:3, :3].T + self.to_world_m[:3, 3]

    def integrator_properties(self):
        """``voldis`` integrator properties describing this space (empty for world space), typed as
        Mitsuba reads them (``mi.load_dict``; :mod:`mi_voldis.io.scene_xml` writes them as XML)."""
        if self.is_world:
            return {}
        if self.is_curved:
            return {"contract_to_world": to_scalar_transform(self.to_world_m), "contract_shell": self.shell}
        return {"ndc_to_world": to_scalar_transform(self.to_world_m), "ndc_near": self.near,
                "ndc_scale_x": self.scale[0], "ndc_scale_y": self.scale[1]}

    @classmethod
    def from_box(cls, box):
        """The space of a :class:`SceneBox`."""
        if box.kind == "world":
            return cls()
        if box.kind == "contract":
            return cls("contract", box.to_world, shell=box.shell)
        return cls("ndc", box.ndc_to_world, box.ndc_near, box.ndc_scale)


@dataclass
class SceneBox:
    """Where the fields live. ``kind`` 'world': an axis-aligned box ``lo``..``hi`` in world space.
    ``kind`` 'ndc': forward-facing scenes; the box is in the NDC space of the reference camera
    ``ndc_to_world`` (Mitsuba camera frame) with near plane ``ndc_near`` and scales ``ndc_scale``
    (2 f / W, 2 f / H), as in NeRF's LLFF set-up. ``kind`` 'contract': all of space, contracted
    (``to_world``: normalised -> world, ``shell``: b), the box the cube [-(1 + b), 1 + b]^3."""
    kind: str
    lo: np.ndarray
    hi: np.ndarray
    ndc_to_world: np.ndarray | None = None
    ndc_near: float | None = None
    ndc_scale: tuple | None = None
    to_world: np.ndarray | None = None
    shell: float = 1.0
    near: float = 0.0  # world distance from the cameras before which nothing is (rays start there)
