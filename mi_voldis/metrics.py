"""Image metrics on display-encoded images in [0, 1]: PSNR, SSIM, mask IoU."""
import numpy as np

# the removed region a removal is scored in: the object's mask dilated by this fraction of the image
# diagonal (the hole's soft edge counts, as the 2D inpainters' masks are dilated alike). A constant of the
# protocol, not the fit's ``hull_dilation``: a fit that grows its hull must not change what it is scored on
SCORE_DILATION = 0.03


def diagonal_pixels(fraction, size):
    """``fraction`` of the diagonal of an image of ``size`` ((width, height) or (height, width)), in whole
    pixels rounded up: how far masks and rings are grown, whatever the resolution."""
    return int(np.ceil(fraction * np.hypot(*size)))


def score_dilation(size):
    """Pixels the masks are dilated by for scoring an image of ``size`` (width, height)."""
    return diagonal_pixels(SCORE_DILATION, size)


def psnr(a, b, mask=None):
    """Peak signal-to-noise ratio in dB (peak 1); over the pixels of ``mask`` when given."""
    err = (np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2
    if mask is not None:
        err = err[np.asarray(mask, bool)]
    mse = float(err.mean()) if err.size else np.nan
    return float("inf") if mse == 0 else -10.0 * np.log10(mse)


def _gaussian_blur(x, sigma=1.5, radius=5):
    k = np.exp(-0.5 * (np.arange(-radius, radius + 1) / sigma) ** 2)
    k /= k.sum()
    for axis in (0, 1):
        x = np.apply_along_axis(lambda v: np.convolve(v, k, mode="valid"), axis, x)
    return x


def ssim_map(a, b):
    """Per-pixel SSIM (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 = 0.01, K2 = 0.03),
    averaged over channels; the map is 10 pixels smaller than the images (valid window positions)."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    c1, c2 = 0.01 ** 2, 0.03 ** 2
    out = []
    for ch in range(a.shape[2]):
        x, y = a[..., ch], b[..., ch]
        mx, my = _gaussian_blur(x), _gaussian_blur(y)
        sxx = _gaussian_blur(x * x) - mx * mx
        syy = _gaussian_blur(y * y) - my * my
        sxy = _gaussian_blur(x * y) - mx * my
        out.append((2 * mx * my + c1) * (2 * sxy + c2) / ((mx * mx + my * my + c1) * (sxx + syy + c2)))
    return np.mean(out, axis=0)


def ssim(a, b, mask=None):
    """Mean SSIM; over the window centres inside ``mask`` when given."""
    m = ssim_map(a, b)
    if mask is None:
        return float(m.mean())
    inner = np.asarray(mask, bool)[5:-5, 5:-5]
    return float(m[inner].mean()) if inner.any() else np.nan


def iou(a, b):
    a, b = np.asarray(a, bool), np.asarray(b, bool)
    union = np.logical_or(a, b).sum()
    return float(np.logical_and(a, b).sum() / union) if union else np.nan


def dilate(mask, radius):
    """Binary dilation by a (2 radius + 1)^2 square (separable), on (H, W) or (N, H, W) masks."""
    out = np.asarray(mask, bool)
    for axis in (-2, -1):
        src, out = out, out.copy()
        n = src.shape[axis]
        for shift in range(1, min(radius, n - 1) + 1):
            lo = [slice(None)] * src.ndim
            hi = [slice(None)] * src.ndim
            lo[axis], hi[axis] = slice(0, n - shift), slice(shift, n)
            out[tuple(lo)] |= src[tuple(hi)]
            out[tuple(hi)] |= src[tuple(lo)]
    return out


def object_residue(render, photo, background, mask, min_difference=0.1):
    """Fraction of the object's pixels (``mask``) where a removal ``render`` is closer to the photo (the
    object's own colour) than to the ground-truth ``background``: 0 when no trace of the object is left,
    1 when the object is still there. Pixels where photo and background differ by less than
    ``min_difference`` (RGB distance) say nothing either way and are left out; NaN when none is left."""
    render, photo, background = (np.asarray(x, np.float64) for x in (render, photo, background))
    telling = np.asarray(mask, bool) & (np.linalg.norm(photo - background, axis=-1) > min_difference)
    if not telling.any():
        return float("nan")
    to_photo = np.linalg.norm(render - photo, axis=-1)[telling]
    to_background = np.linalg.norm(render - background, axis=-1)[telling]
    return float(np.mean(to_photo < to_background))
