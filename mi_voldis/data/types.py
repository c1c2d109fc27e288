"""Typed dataset records: images, cameras, object masks, splits, ground truth."""
from dataclasses import dataclass, field

import numpy as np

from ..cameras import Camera
from ..space import SceneBox


class DatasetError(ValueError):
    """A dataset file is missing, unreadable or inconsistent; the message names the file."""


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
    cameras: list[Camera]
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
