"""Pixels of a set of views as rays: random batches for training, whole views for evaluation.

Colours, masks and camera parameters live on the device; a batch is a set of pixel indices, turned
into world rays there (a random position inside each pixel, as a box-filtered film integrates).

Colours and the mask bit are kept as one UInt32 a pixel (4 bytes where float colours and mask take 16:
half a GiB on a 185-view capture at 512^2), three codes of ``bits`` bits each and the mask above them,
decoded through a table of ``2^bits`` levels:
- photographs stored at 8 bits (every value one of k / 255): their 8-bit codes, decoded through a table of the
  very floats the dataset holds, so a batch's colours are the dataset's bit for bit;
- other images in [0, 1] (undistorted or resized photographs, inpainted guides): 10-bit codes k / 1023, off
  the dataset's values by at most half a 10-bit step (4.9e-4, a quarter of the photograph's own 8-bit step;
  the rounding's noise alone would be 71 dB PSNR);
- images with values outside [0, 1] or NaN (images a caller made): float colours and a float mask (none where
  the dataset has no masks).

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
        masks = dataset.masks[self.views] if dataset.masks is not None else np.zeros((n, h, w), bool)
        self.masks_np = masks
        packed = packed_pixels(dataset.images, self.views, masks)
        self.codes = None if packed is None else mi.UInt32(packed[0].reshape(-1))
        self.bits = None if packed is None else packed[1]
        if packed is None:
            self.colors = mi.Float(dataset.images[self.views].reshape(-1))
            # no masks: no array of zeros (a batch's mask is then a constant)
            self.masks = None if dataset.masks is None else mi.Float(masks.reshape(-1).astype(np.float32))
        else:
            self.levels = mi.Float(LEVELS[self.bits])
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
        if self.codes is None:
            color = dr.gather(mi.Color3f, self.colors, index)
            mask = dr.zeros(mi.Float, dr.width(index)) if self.masks is None else dr.gather(mi.Float, self.masks, index)
        else:
            code = dr.gather(mi.UInt32, self.codes, index)
            top, bits = (1 << self.bits) - 1, self.bits
            color = mi.Color3f(*(dr.gather(mi.Float, self.levels, (code >> (k * bits)) & top) for k in range(3)))
            mask = mi.Float(code >> (3 * bits))
        return o, d, color, mask, view


# the floats an 8-bit photograph holds once read (mi_voldis.data.images: code / 255 in float32), and the
# levels of the 10-bit codes of other images in [0, 1]
EIGHT_BIT_LEVELS = np.arange(256, dtype=np.float32) / np.float32(255)
LEVELS = {8: EIGHT_BIT_LEVELS, 10: np.arange(1024, dtype=np.float32) / np.float32(1023)}


def quantized(image, bits):
    """uint32 codes of the nearest of LEVELS[``bits``] to each value of ``image`` (clipped to [0, 1])."""
    top = (1 << bits) - 1
    with np.errstate(invalid="ignore"):  # a NaN casts to some integer: kept in range, code_bits refuses it
        return np.minimum(np.rint(np.clip(image, 0.0, 1.0) * top).astype(np.uint32), top)


def code_bits(images, views):
    """8 where every value of the ``views`` of ``images`` is one of EIGHT_BIT_LEVELS, else 10 where every
    value is in [0, 1], else None (a value above 1, below 0 or NaN, which fails both comparisons)."""
    if all(np.array_equal(EIGHT_BIT_LEVELS[quantized(images[v], 8)], images[v]) for v in views):
        return 8
    with np.errstate(invalid="ignore"):
        if all(((images[v] >= 0.0) & (images[v] <= 1.0)).all() for v in views):
            return 10
    return None


def packed_pixels(images, views, masks):
    """((n, H, W) uint32, bits) of the ``views`` of float ``images``: the codes of R, G and B
    (:func:`quantized`), ``bits`` (:func:`code_bits`) each from bit 0, and the (n, H, W) bool ``masks`` in
    bit 3 ``bits``; None where the images have values outside [0, 1]. A view at a time: no float copy of
    the images."""
    bits = code_bits(images, views)
    if bits is None:
        return None
    out = np.empty(masks.shape, np.uint32)
    for i, v in enumerate(views):
        c = quantized(images[v], bits)
        out[i] = c[..., 0] | (c[..., 1] << bits) | (c[..., 2] << 2 * bits) | (masks[i].astype(np.uint32) << 3 * bits)
    return out, bits


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


def tile_pairs(tiles, tile):
    """(n, 2) uint32: the ray indices of every horizontally and vertically adjacent pixel pair in a batch
    of ``tiles`` tiles of ``tile`` x ``tile`` rays, row-major per tile (:func:`tile_pixels`' order)."""
    y, x = np.divmod(np.arange(tile * tile), tile)
    right, down = np.flatnonzero(x + 1 < tile), np.flatnonzero(y + 1 < tile)
    pairs = np.concatenate([np.stack([right, right + 1], 1), np.stack([down, down + tile], 1)])
    return (np.arange(tiles)[:, None, None] * tile * tile + pairs[None]).reshape(-1, 2).astype(np.uint32)
