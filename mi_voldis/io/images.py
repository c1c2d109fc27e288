"""8-bit images and colour encodings.

Radiance fields here hold *display-encoded* (sRGB) colour, as the photographs they are fitted to and
as NeRF does: their renders are quantised to PNG as they are (:func:`display_to_uint8`). Mitsuba's
path tracer renders *linear* light, encoded with the sRGB curve for PNG (:func:`linear_to_uint8`).
EXR layers are written in linear light (:mod:`mi_voldis.compositing`), as compositing
tools expect."""
import os

import imageio.v3 as iio
import numpy as np

from .run_folder import temp_beside


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


def depth_to_uint8(z, alpha=None, bar=True):
    """Depth map -> colour uint8 (matplotlib's viridis, near = bright), over the 1st..99th percentile of
    the pixels with alpha > 0.5 (black elsewhere); ``bar``: on images at least 96 pixels wide, a colour
    bar at the right edge labelled with that range in world units (distance along the ray)."""
    from matplotlib import colormaps
    z = np.asarray(z, dtype=np.float64)
    mask = (np.asarray(alpha) > 0.5) if alpha is not None else z > 0
    if not mask.any():
        return np.zeros(z.shape + (3,), np.uint8)
    lo, hi = np.percentile(z[mask], [1, 99])
    v = np.clip(1.0 - (z - lo) / max(hi - lo, 1e-8), 0, 1)
    cmap = colormaps["viridis"]
    img = np.where(mask[..., None], cmap(v)[..., :3], 0.0)
    img = (img * 255).astype(np.uint8)
    h, w = z.shape
    if bar and w >= 96:
        import cv2
        bw = max(6, w // 40)
        ramp = cmap(np.linspace(1, 0, h))[:, :3]  # near (bright) at the top
        img[:, w - bw:] = (ramp[:, None, :] * 255).astype(np.uint8)
        scale = max(0.3, min(0.5, w / 640))
        for text, y in ((f"{lo:.3g}", int(14 * scale / 0.4)), (f"{hi:.3g} units", h - 4)):
            size = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)[0][0]
            cv2.putText(img, text, (w - bw - size - 3, y), cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), 1,
                        cv2.LINE_AA)
    return img


def write_png(path, image):
    """Write a uint8 image, via a temporary file so nothing is left half-written."""
    tmp = temp_beside(path, ".png")
    iio.imwrite(tmp, image)
    os.replace(tmp, path)


def contact_sheet(images, columns=None, pad=4, labels=None):
    """Tile uint8 images into a grid on a white background, ``columns`` per row (default: one row);
    ``labels``: a caption above each tile (black on the white margin)."""
    if not images:
        raise ValueError("contact_sheet needs at least one image")
    h = max(im.shape[0] for im in images)
    w = max(im.shape[1] for im in images)
    columns = columns or len(images)
    rows = (len(images) + columns - 1) // columns
    scale = max(0.3, min(0.5, w / 320))  # OpenCV's Hershey font: ~22 px tall at scale 1
    band = int(round(24 * scale)) + 4 if labels else 0
    sheet = np.full((rows * (h + pad + band) + pad, columns * (w + pad) + pad, 3), 255, np.uint8)
    for n, im in enumerate(images):
        r, c = divmod(n, columns)
        y, x = pad + r * (h + pad + band) + band, pad + c * (w + pad)
        sheet[y:y + im.shape[0], x:x + im.shape[1]] = im[..., :3]
        if labels and n < len(labels) and labels[n]:
            import cv2
            cv2.putText(sheet, str(labels[n]), (x + 1, y - 4), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 1,
                        cv2.LINE_AA)
    return sheet
