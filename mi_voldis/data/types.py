"""Typed dataset records: cameras in Mitsuba's convention, images, object masks, splits, ground truth."""
from dataclasses import dataclass, field

import numpy as np


class DatasetError(ValueError):
    """A dataset file is missing, unreadable or inconsistent; the message names the file."""


@dataclass
class Camera:
    """A pinhole camera in Mitsuba's convention.

    ``to_world``: rigid 4x4 camera-to-world matrix whose axes are Mitsuba's camera frame (+x left,
    +y up, +z forward); ``fov_x``: horizontal field of view in degrees; ``principal``: Mitsuba's
    ``principal_point_offset_x/y`` (principal point = film centre minus ``principal`` times the film
    size; OpenCV's cx = W (0.5 - principal_x), cy = H (0.5 - principal_y))."""
    to_world: np.ndarray
    fov_x: float
    width: int
    height: int
    principal: tuple = (0.0, 0.0)

    @property
    def focal(self):
        """Focal length in pixels."""
        return 0.5 * self.width / np.tan(np.radians(self.fov_x) / 2)

    def sensor_dict(self, spp=1, near_clip=1e-4):
        """Plugin dict of the equivalent Mitsuba ``perspective`` sensor with a box-filtered RGB film."""
        import mitsuba as mi
        return {"type": "perspective", "fov": float(self.fov_x), "fov_axis": "x", "near_clip": near_clip,
                "principal_point_offset_x": float(self.principal[0]),
                "principal_point_offset_y": float(self.principal[1]),
                "to_world": mi.ScalarTransform4f(np.asarray(self.to_world, np.float32)),
                "film": {"type": "hdrfilm", "width": int(self.width), "height": int(self.height),
                         "pixel_format": "rgb", "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": spp}}


@dataclass
class SceneBox:
    """Where the fields live. ``kind`` 'world': an axis-aligned box ``lo``..``hi`` in world space.
    ``kind`` 'ndc': forward-facing scenes; the box is in the NDC space of the reference camera
    ``ndc_to_world`` (Mitsuba camera frame) with near plane ``ndc_near`` and scales ``ndc_scale``
    (2 f / W, 2 f / H), as in NeRF's LLFF set-up; see :mod:`mi_voldis.render.space`."""
    kind: str
    lo: np.ndarray
    hi: np.ndarray
    ndc_to_world: np.ndarray | None = None
    ndc_near: float | None = None
    ndc_scale: tuple | None = None


@dataclass
class Dataset:
    """Posed images of one scene and a mask of one object per view.

    ``images``: (N, H, W, 3) float32 in [0, 1], display-encoded (sRGB) as stored in the files;
    ``masks``: (N, H, W) bool (object = True) or None; ``split``: per-view 'train' or 'test';
    ``backgrounds``/``moved``: ground truth without the object / with it moved by
    ``moved_transform`` (None where the dataset has none; NaN images for views without them).
    ``meta['background_color']``: set when RGBA images were composited over that colour (what a ray
    leaving the scene sees); absent for captures where every ray ends on a surface."""
    name: str
    root: str
    names: list
    images: np.ndarray
    cameras: list
    split: np.ndarray
    box: SceneBox
    masks: np.ndarray | None = None
    coverage: np.ndarray | None = None
    near_far: np.ndarray | None = None
    backgrounds: np.ndarray | None = None
    moved: np.ndarray | None = None
    moved_transform: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __repr__(self):
        return (f"Dataset({self.name!r}, {len(self.images)} views of {self.size[1]}x{self.size[0]}, "
                f"{len(self.train)} train / {len(self.test)} test, box={self.box.kind}, "
                f"masks={'yes' if self.masks is not None else 'no'})")

    @property
    def train(self):
        return np.flatnonzero(self.split == "train")

    @property
    def test(self):
        return np.flatnonzero(self.split == "test")

    @property
    def size(self):
        """(height, width) of every image."""
        return self.images.shape[1:3]
