"""8-bit images and colour encodings.

Radiance fields here hold *display-encoded* (sRGB) colour, as the photographs they are fitted to and
as NeRF does: their renders are quantised to PNG as they are (:func:`display_to_uint8`). Mitsuba's
path tracer renders *linear* light, encoded with the sRGB curve for PNG (:func:`linear_to_uint8`).
EXR layers are written in linear light (:mod:`mi_voldis.compositing`), as compositing
tools expect."""
import os

import imageio.v3 as iio
import numpy as np


def linear_to_srgb(x):
    """IEC 61966-2-1 transfer function, input clipped to [0, 1]."""
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def srgb_to_linear(x):
    x = np.asarray(x, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def linear_to_uint8(rgb):
    """(H, W, 3) linear RGB -> sRGB-encoded uint8."""
    return np.round(linear_to_srgb(rgb) * 255.0).astype(np.uint8)


def display_to_uint8(rgb):
    """(H, W, 3) display-encoded RGB in [0, 1] -> uint8 (no transfer curve)."""
    return np.round(np.clip(rgb, 0.0, 1.0) * 255.0).astype(np.uint8)


def depth_to_uint8(z, alpha=None):
    """Depth map -> grey uint8, near = bright, normalised over pixels with alpha > 0.5."""
    z = np.asarray(z, dtype=np.float64)
    mask = (np.asarray(alpha) > 0.5) if alpha is not None else z > 0
    if not mask.any():
        return np.zeros(z.shape + (3,), np.uint8)
    lo, hi = np.percentile(z[mask], [1, 99])
    v = np.where(mask, 1.0 - (z - lo) / max(hi - lo, 1e-8), 0.0)
    return np.repeat((np.clip(v, 0, 1) * 255).astype(np.uint8)[..., None], 3, axis=2)


def write_png(path, image):
    """Write a uint8 image, via a temporary file so nothing is left half-written."""
    tmp = f"{path}.tmp.png"
    iio.imwrite(tmp, image)
    os.replace(tmp, path)


def contact_sheet(images, columns=None, pad=4):
    """Tile uint8 images into a grid on a white background, ``columns`` per row (default: one row)."""
    if not images:
        raise ValueError("contact_sheet needs at least one image")
    h = max(im.shape[0] for im in images)
    w = max(im.shape[1] for im in images)
    columns = columns or len(images)
    rows = (len(images) + columns - 1) // columns
    sheet = np.full((rows * (h + pad) + pad, columns * (w + pad) + pad, 3), 255, np.uint8)
    for n, im in enumerate(images):
        r, c = divmod(n, columns)
        y, x = pad + r * (h + pad), pad + c * (w + pad)
        sheet[y:y + im.shape[0], x:x + im.shape[1]] = im[..., :3]
    return sheet
