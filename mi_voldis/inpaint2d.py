"""2D inpainting: the image inpainters a background prior can use, and the fill of a depth map.

An *inpainter* is any callable ``(image (H, W, 3) float in [0, 1], hole (H, W) bool) -> (H, W, 3)``
that replaces the hole's pixels; :data:`INPAINTERS` names the built-in ones (OpenCV's Telea and
Navier-Stokes, and the harmonic membrane). A learned inpainter (LaMa and the like) plugs in through the same signature.

Depth is filled as disparity q = 1 / depth: on a plane, q is an affine function of the pixel
coordinates (for a pinhole camera, n . X = c along the ray X = o + t d makes 1/t linear in d, and d is
projectively linear in (x, y)), so a robust affine fit to the ring around the hole plus a harmonic
(Laplace) fill of what the plane does not explain continues planes exactly and other surfaces smoothly.
"""
import numpy as np

from .metrics import dilate


def opencv_inpaint(image, hole, method="telea", radius=5):
    """OpenCV's inpainting ('telea' or 'ns') of ``image`` (H, W, 3) in [0, 1] inside ``hole``."""
    import cv2
    flag = {"telea": cv2.INPAINT_TELEA, "ns": cv2.INPAINT_NS}[method]
    img8 = np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)
    out = cv2.inpaint(img8, np.asarray(hole, np.uint8) * 255, radius, flag)
    return out.astype(np.float32) / 255.0


def membrane_inpaint(image, hole):
    """The smoothest fill: each channel's harmonic extension from the hole's boundary (:func:`harmonic_fill`)."""
    return np.stack([harmonic_fill(image[..., c], hole) for c in range(image.shape[-1])], -1).astype(np.float32)


INPAINTERS = {
    "telea": lambda image, hole: opencv_inpaint(image, hole, "telea"),
    "ns": lambda image, hole: opencv_inpaint(image, hole, "ns"),
    "membrane": membrane_inpaint,
}


def inpainter(name_or_callable):
    """The inpainter named ``name_or_callable`` in :data:`INPAINTERS`, or the callable itself."""
    if callable(name_or_callable):
        return name_or_callable
    if name_or_callable not in INPAINTERS:
        raise ValueError(f"unknown inpainter {name_or_callable!r}: one of {', '.join(INPAINTERS)} or a callable")
    return INPAINTERS[name_or_callable]


def harmonic_fill(values, hole, iterations=200):
    """``values`` (H, W) with the ``hole`` pixels replaced by the solution of Laplace's equation whose
    boundary values are the known pixels around them (Neumann at the image border). Solved coarse to
    fine: each level starts from the half-resolution solution, then relaxes with Jacobi steps."""
    v = np.where(hole, 0.0, values).astype(np.float64)
    hole = np.asarray(hole, bool)
    if not hole.any():
        return v
    h, w = hole.shape
    if min(h, w) >= 8 and hole.sum() > 64:
        hh, ww = (h + 1) // 2, (w + 1) // 2
        known = np.zeros((2 * hh, 2 * ww))
        total = np.zeros((2 * hh, 2 * ww))
        known[:h, :w] = ~hole
        total[:h, :w] = np.where(hole, 0.0, v)
        k = known.reshape(hh, 2, ww, 2).sum((1, 3))
        s = total.reshape(hh, 2, ww, 2).sum((1, 3))
        coarse = harmonic_fill(np.where(k > 0, s / np.maximum(k, 1), 0.0), k == 0, iterations)
        v[hole] = np.repeat(np.repeat(coarse, 2, 0), 2, 1)[:h, :w][hole]
    else:
        v[hole] = v[~hole].mean() if (~hole).any() else 0.0
    for _ in range(iterations):
        p = np.pad(v, 1, mode="edge")
        v[hole] = (0.25 * (p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:]))[hole]
    return v


def fill_disparity(depth, hole, known=None, ring=4):
    """``depth`` (H, W, distances along the rays) with the ``hole`` filled: a robust affine fit of the
    disparity 1 / depth on the ``ring`` pixels around the hole (``known`` pixels only), plus the harmonic
    fill of its residual. Exact for a plane seen on every side of the hole."""
    hole = np.asarray(hole, bool)
    known = ~hole if known is None else np.asarray(known, bool) & ~hole
    if not hole.any():
        return np.asarray(depth, np.float64).copy()
    if not known.any():
        raise ValueError("no known depth around the hole to fill it from")
    q = np.where(known, 1.0 / np.maximum(depth, 1e-9), 0.0)
    band = dilate(hole, ring) & known
    if band.sum() < 3:
        band = known
    y, x = np.nonzero(band)
    a = np.stack([x, y, np.ones_like(x)], -1).astype(np.float64)
    b = q[band]
    keep = np.ones(len(b), bool)
    for _ in range(3):  # trim the ring pixels the plane explains worst (an occluder's edge)
        coef = np.linalg.lstsq(a[keep], b[keep], rcond=None)[0]
        r = np.abs(a @ coef - b)
        cut = 3.0 * np.median(r[keep]) + 1e-12
        if (r[keep] <= cut).sum() < 3 or (r[keep] <= cut).all():
            break
        keep &= r <= cut
    yy, xx = np.mgrid[0:hole.shape[0], 0:hole.shape[1]]
    plane = coef[0] * xx + coef[1] * yy + coef[2]
    unknown = hole | ~known
    residual = harmonic_fill(np.where(unknown, 0.0, q - plane), unknown)
    filled = np.maximum(plane + residual, 1e-6)
    out = np.asarray(depth, np.float64).copy()
    out[hole] = 1.0 / filled[hole]
    return out
