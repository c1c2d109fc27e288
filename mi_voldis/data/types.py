"""Typed dataset records: images, cameras, object masks, splits, ground truth."""
from dataclasses import dataclass, field

import numpy as np

from ..cameras import Camera
from ..space import SceneBox


def spread(n, count):
    """Indices of up to ``count`` of ``n`` items (views), spread evenly from the first to the last: all of
    them when ``count`` >= ``n``."""
    return np.unique(np.linspace(0, n - 1, min(count, n)).round().astype(int))


class DatasetError(ValueError):
    """A dataset file is missing, unreadable or inconsistent; the message names the file."""


@dataclass
class Dataset:
    """Posed images of one scene and a mask of one object per view.

    ``images``: (N, H, W, 3) float32 in [0, 1], display-encoded (sRGB) as stored in the files;
    ``masks``: (N, H, W) bool (object = True) or None; ``masked``: (N,) bool, False for views that came
    without a mask (their mask is all True: they train the full field only, nothing of the background)
    or None when every view has one; ``split``: per-view 'train' or 'test';
    ``effects``: (N, H, W) bool or None: pixels outside the object's mask that the object changes (its
    shadow, its reflection), where the photos show the object's effect rather than the background;
    ``backgrounds``/``moved``: ground truth without the object / with it moved by
    ``moved_transform`` (None where the dataset has none; NaN images for views without them).
    ``ignore``: (N, H, W) bool or None: pixels to leave out of training (nerfstudio's ``mask_path``,
    black = ignore); the ray bank draws training batches from the others.
    ``points``: (P, 3) sparse world points of the capture (COLMAP, ``ply_file_path``) or None.
    ``meta['notes']``: lines for the user about how the files were read (printed by the fit).
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
    effects: np.ndarray | None = None
    near_far: np.ndarray | None = None
    backgrounds: np.ndarray | None = None
    moved: np.ndarray | None = None
    moved_transform: np.ndarray | None = None
    masked: np.ndarray | None = None
    points: np.ndarray | None = None
    ignore: np.ndarray | None = None
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
    def masked_train(self):
        """Training views with an object mask of their own (those the background and the hull learn from)."""
        if self.masks is None:
            return np.zeros(0, np.int64)
        return self.train if self.masked is None else self.train[self.masked[self.train]]

    @property
    def size(self):
        """(height, width) of every image."""
        return self.images.shape[1:3]

    def as_photographed(self, layer):
        """What a photograph of this dataset shows of a rendered layer ``(rgb, alpha, ...)`` (H, W, 3
        premultiplied and H, W, as :func:`~mi_voldis.render.views.render_camera` gives it): the layer over
        ``meta['background_color']`` where the images were composited over one (the rays that leave the
        scene see it), else its RGB (every ray of a capture ends on something), as training compares."""
        rgb, alpha = layer[0], layer[1]
        color = self.meta.get("background_color")
        if color is None:
            return rgb
        return rgb + (1.0 - alpha)[..., None] * np.asarray(color, rgb.dtype)
