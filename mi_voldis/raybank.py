"""Pixels of a set of views as rays: random batches for training, whole views for evaluation.

Colours, masks and camera parameters live on the device; a batch is a set of pixel indices, turned
into world rays there (a random position inside each pixel, as a box-filtered film integrates).

A batch can come in t x t pixel tiles (each around a random pixel of a random view): the rays of a
tile march side by side through the same cells, so the grid lookups of one SIMD packet share cache
lines. Pixels are still drawn uniformly (up to clipping at image borders).
"""
import drjit as dr
import mitsuba as mi
import numpy as np

from .cameras import CameraTable
from .device import from_numpy


class RayBank:
    def __init__(self, dataset, views):
        self.views = np.asarray(views)
        n, (h, w) = len(self.views), dataset.size
        self.height, self.width = h, w
        self.colors = mi.Float(dataset.images[self.views].reshape(-1))
        masks = dataset.masks[self.views] if dataset.masks is not None else np.zeros((n, h, w), bool)
        self.masks_np = masks
        self.masks = mi.Float(masks.reshape(-1).astype(np.float32))
        # nerfstudio's pixels to ignore: batches without a pool of their own draw from the others
        ignore = dataset.ignore[self.views] if dataset.ignore is not None else None
        self.ignore_np = ignore
        self.keep = None if ignore is None else np.flatnonzero(~ignore.reshape(-1)).astype(np.uint32)
        self.table = CameraTable([dataset.cameras[v] for v in self.views])
        self.cams = self.table.cameras

    @property
    def pixels(self):
        return len(self.views) * self.height * self.width

    def batch(self, rng, n, pool=None, tile=1):
        """Rays, colours, masks and views (indices into this bank's views) of ``n`` random pixels (of
        ``pool``, flat indices, when given, else of the pixels the dataset does not mark to ignore), each
        at a random position inside its pixel; ``tile`` > 1: in tiles of tile x tile pixels, each around a
        random pixel (of ``pool``)."""
        pool = self.keep if pool is None else pool
        count = -(-n // (tile * tile))
        anchors = rng.integers(0, self.pixels, count) if pool is None else pool[rng.integers(0, len(pool), count)]
        idx = tile_pixels(rng, anchors, tile, self.height, self.width)[:n] if tile > 1 else anchors
        return self.rays(idx.astype(np.uint32), rng.random((n, 2), np.float32))

    def rays(self, index, jitter):
        """World rays (o, d), colours, masks and views (UInt32, indices into this bank's views) of flat
        pixel indices; ``jitter`` (n, 2) in [0, 1) places each ray inside its pixel."""
        index = from_numpy(mi.UInt32, index)
        hw = self.height * self.width
        view = index // hw
        pix = index - view * hw
        py = pix // self.width
        px = pix - py * self.width
        u = (mi.Float(px) + from_numpy(mi.Float, jitter[:, 0])) / self.width
        v = (mi.Float(py) + from_numpy(mi.Float, jitter[:, 1])) / self.height
        o, d = self.table.rays(view, u, v)
        color = dr.gather(mi.Color3f, self.colors, index)
        mask = dr.gather(mi.Float, self.masks, index)
        return o, d, color, mask, view


def tile_pixels(rng, anchors, tile, height, width):
    """Flat pixel indices (view * H * W + y * W + x) of ``tile`` x ``tile`` tiles, one per anchor pixel,
    each at a random offset that contains its anchor, clipped to the image; row-major per tile."""
    view, pixel = np.divmod(np.asarray(anchors, np.int64), height * width)
    y0 = np.clip(pixel // width - rng.integers(0, tile, len(view)), 0, max(height - tile, 0))
    x0 = np.clip(pixel % width - rng.integers(0, tile, len(view)), 0, max(width - tile, 0))
    dy, dx = np.divmod(np.arange(tile * tile), tile)
    y = np.minimum(y0[:, None] + dy, height - 1)
    x = np.minimum(x0[:, None] + dx, width - 1)
    return (view[:, None] * (height * width) + y * width + x).ravel()
