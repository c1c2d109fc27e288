"""2D inpainting: the image inpainters a background prior can use, and the fill of a depth map.

An *inpainter* is any callable ``(image (H, W, 3) float in [0, 1], hole (H, W) bool) -> (H, W, 3)``
that replaces the hole's pixels; :data:`INPAINTERS` names the built-in ones (OpenCV's Telea and
Navier-Stokes, OpenCV contrib's frequency-selective reconstruction, the harmonic membrane and the
row-wise fill from beside the hole), 'auto' the best one installed: 'fsr' where OpenCV has its contrib
modules, else 'telea', and names joined by '+' the mean of their fills (:func:`blend`). A learned
inpainter (LaMa and the like) plugs in through the same signature.

Depth is filled as disparity q = 1 / z (z: depth along the optical axis): on a plane, q is an affine
function of the pixel coordinates (a point X = z (x', y', 1) in the camera frame, x' and y' affine in
the pixel coordinates, lies on n . X = c exactly when 1 / z = n . (x', y', 1) / c), so a robust
affine fit to the ring around the hole plus a harmonic (Laplace) fill of what the plane does not
explain continues planes exactly and other surfaces smoothly.
"""
import numpy as np

from .cameras import pixel_rays
from .metrics import dilate


def opencv_inpaint(image, hole, method="telea", radius=5):
    """OpenCV's inpainting ('telea' or 'ns') of ``image`` (H, W, 3) in [0, 1] inside ``hole``."""
    import cv2
    flag = {"telea": cv2.INPAINT_TELEA, "ns": cv2.INPAINT_NS}[method]
    img8 = np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)
    out = cv2.inpaint(img8, np.asarray(hole, np.uint8) * 255, radius, flag)
    return out.astype(np.float32) / 255.0


def fsr_inpaint(image, hole):
    """OpenCV contrib's frequency-selective reconstruction (``cv2.xphoto``, FSR_FAST; Genser et al.
    2018): each block of the hole is modelled as a sparse sum of DCT basis functions fitted to the
    known pixels around it, so stripes, checks and other textures continue through the hole where
    Telea and Navier-Stokes smear them."""
    import cv2
    if not hasattr(cv2, "xphoto"):
        raise RuntimeError("inpainter 'fsr' needs OpenCV's contrib modules (cv2.xphoto): pip install "
                           "opencv-contrib-python-headless, or --set prior_inpainter=\"auto\" (the best one installed)")
    img8 = np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)
    out = np.zeros_like(img8)
    cv2.xphoto.inpaint(img8, np.where(hole, 0, 255).astype(np.uint8), out, cv2.xphoto.INPAINT_FSR_FAST)
    return np.where(np.asarray(hole, bool)[..., None], out, img8).astype(np.float32) / 255.0  # known pixels kept


def membrane_inpaint(image, hole):
    """The smoothest fill: each channel's harmonic extension from the hole's boundary (:func:`harmonic_fill`)."""
    return np.stack([harmonic_fill(image[..., c], hole) for c in range(image.shape[-1])], -1).astype(np.float32)


def lateral_inpaint(image, hole, band=3, smooth=2):
    """Each row of the hole filled across, from the colours beside it: a run of hole pixels [a, b] takes
    the linear interpolation between the mean of the (up to) ``band`` known pixels just left of it and
    of those just right of it, each placed at its pixels' mean column (exact where the colour is affine
    along the row); with known pixels on one side only, that side's mean. The fill is then averaged over
    ``2 smooth + 1`` rows among the hole's own pixels (a row's few neighbours are noisy); rows with no
    known pixel beside a run take the harmonic fill of the rest (:func:`membrane_inpaint`).

    The surfaces an object hides on a level camera are mostly horizontal bands (floor, the wall's foot,
    a path, a hedge) that run on behind it, and the object's own contact shadow lies under it: a fill
    from every side (Telea, Navier-Stokes, FSR) carries what stands below the hole upward through it (a
    pedestal's top, the shadow), this one only what stands beside it."""
    hole = np.asarray(hole, bool)
    out = np.asarray(image, np.float32).copy()
    w = hole.shape[1]
    cols = np.arange(w)
    done = ~hole  # known, or filled from beside
    for y in np.nonzero(hole.any(1))[0]:
        row = hole[y]
        edges = np.flatnonzero(np.diff(np.concatenate([[0], row.astype(np.int8), [0]])))
        for a, b in zip(edges[0::2], edges[1::2] - 1):  # the row's hole runs [a, b]
            left, right = cols[max(a - band, 0):a], cols[b + 1:b + 1 + band]
            left, right = left[~row[left]], right[~row[right]]
            if not len(left) and not len(right):
                continue  # left to the harmonic fill
            if len(left) and len(right):
                t = (np.arange(a, b + 1) - left.mean()) / (right.mean() - left.mean())
                out[y, a:b + 1] = (1 - t)[:, None] * out[y, left].mean(0) + t[:, None] * out[y, right].mean(0)
            else:
                out[y, a:b + 1] = out[y, left if len(left) else right].mean(0)
            done[y, a:b + 1] = True
    if smooth:
        out = _blur_rows_within(out, hole & done, smooth)
    if not done.all():
        out = membrane_inpaint(out, ~done)
    return out


def _blur_rows_within(image, mask, r):
    """``image`` with each ``mask`` pixel replaced by the mean of the ``mask`` pixels of its column within ``r``
    rows of it (a box filter along the columns, normalised over the mask)."""
    m = np.pad(mask.astype(np.float64), ((r + 1, r), (0, 0)))
    v = np.pad(np.where(mask[..., None], image, 0.0), ((r + 1, r), (0, 0), (0, 0)))
    cm, cv = np.cumsum(m, 0), np.cumsum(v, 0)
    k = 2 * r + 1
    count, total = cm[k:] - cm[:-k], cv[k:] - cv[:-k]  # rows y - r .. y + r
    return np.where(mask[..., None], total / np.maximum(count, 1)[..., None], image).astype(np.float32)


INPAINTERS = {
    "telea": lambda image, hole: opencv_inpaint(image, hole, "telea"),
    "ns": lambda image, hole: opencv_inpaint(image, hole, "ns"),
    "membrane": membrane_inpaint,
    "fsr": fsr_inpaint,
    "lateral": lateral_inpaint,
}


BASELINES = {"telea": "OpenCV Telea", "ns": "OpenCV Navier-Stokes", "fsr": "OpenCV contrib FSR"}
"""What a user would inpaint in 2D instead (on each view itself), compared in every removal report."""


# 'auto' without OpenCV's contrib modules: in reports/removal.md Telea's in-mask PSNR is above
# Navier-Stokes' on 5 of the 7 ground-truth scenes (FSR, where installed, is best on 5 of 7)
FALLBACK = "telea"


def has_contrib():
    """Whether OpenCV's contrib modules (``cv2.xphoto``, which 'fsr' needs) are installed."""
    import cv2
    return hasattr(cv2, "xphoto")


def resolve(name):
    """The built-in inpainter that the name ``name`` stands for: 'auto' is 'fsr' where OpenCV has its
    contrib modules and :data:`FALLBACK` where not; a blend 'a+b' is its parts resolved; any other name
    itself."""
    if "+" in name:
        return "+".join(resolve(part) for part in name.split("+"))
    if name == "auto":
        return "fsr" if has_contrib() else FALLBACK
    return name


def name_problem(name):
    """Why ``name`` names no inpainter (None when it does): one of :data:`INPAINTERS`, 'auto', or a blend
    of them joined by '+'."""
    unknown = [part for part in name.split("+") if part != "auto" and part not in INPAINTERS]
    if unknown:
        return f"unknown inpainter {unknown[0]!r}: one of auto, {', '.join(INPAINTERS)}, or several joined by '+'"
    return None


def fallback_note(name):
    """The one line that says which inpainter 'auto' (alone or in a blend) uses instead of 'fsr', or None
    when it is 'fsr' (or ``name`` holds no 'auto')."""
    if "auto" not in name.split("+") or has_contrib():
        return None
    return (f"OpenCV has no contrib modules (cv2.xphoto): the 2D prior inpaints with {FALLBACK!r} instead of 'fsr' "
            "(pip install opencv-contrib-python-headless for it)")


def blend(fills):
    """The inpainter whose fill is the mean of ``fills``' (inpainters): fills that fail differently (FSR
    and Telea carry what stands under an object up through the hole, the lateral fill flattens stripes
    that do not run along the rows) can err less together; on the removal family the mean of the two
    won on some scenes and lost on others (reports/notes.md)."""
    def blended(image, hole):
        return (sum(np.asarray(f(image, hole), np.float64) for f in fills) / len(fills)).astype(np.float32)
    return blended


def inpainter(name_or_callable):
    """The inpainter named ``name_or_callable`` in :data:`INPAINTERS` (or 'auto', :func:`resolve`; names
    joined by '+': their :func:`blend`), or the callable itself."""
    if callable(name_or_callable):
        return name_or_callable
    problem = name_problem(name_or_callable)
    if problem:
        raise ValueError(problem)
    if "+" in name_or_callable:
        return blend([inpainter(part) for part in name_or_callable.split("+")])
    return INPAINTERS[resolve(name_or_callable)]


def inpainter_name(name_or_callable):
    """What a run's metrics record as its inpainter: the built-in name 'auto' resolved to (a blend's
    parts resolved), or a callable's ``__name__``."""
    if callable(name_or_callable):
        return getattr(name_or_callable, "__name__", type(name_or_callable).__name__)
    return resolve(name_or_callable)


def available_baselines():
    """The names of :data:`BASELINES` that run here ('fsr' only with OpenCV's contrib modules)."""
    return [name for name in BASELINES if name != "fsr" or has_contrib()]


def harmonic_fill(values, hole, iterations=3000, tol=1e-6):
    """``values`` (H, W) with the ``hole`` pixels replaced by the solution of Laplace's equation whose
    boundary values are the known pixels around them (Neumann at the image border). Solved on the
    hole's bounding box, coarse to fine: each level starts from the half-resolution solution, then
    relaxes with Jacobi steps until no pixel moves by ``tol`` (relative to the data's range)."""
    v = np.where(hole, 0.0, values).astype(np.float64)
    hole = np.asarray(hole, bool)
    if not hole.any():
        return v
    ys, xs = np.nonzero(hole)
    y0, y1 = max(ys.min() - 1, 0), min(ys.max() + 2, hole.shape[0])
    x0, x1 = max(xs.min() - 1, 0), min(xs.max() + 2, hole.shape[1])
    v[y0:y1, x0:x1] = _harmonic(v[y0:y1, x0:x1], hole[y0:y1, x0:x1], iterations, tol)
    return v


def _harmonic(v, hole, iterations, tol):
    h, w = hole.shape
    if min(h, w) >= 8 and hole.sum() > 64:
        hh, ww = (h + 1) // 2, (w + 1) // 2
        known = np.zeros((2 * hh, 2 * ww))
        total = np.zeros((2 * hh, 2 * ww))
        known[:h, :w] = ~hole
        total[:h, :w] = np.where(hole, 0.0, v)
        k = known.reshape(hh, 2, ww, 2).sum((1, 3))
        s = total.reshape(hh, 2, ww, 2).sum((1, 3))
        coarse = _harmonic(np.where(k > 0, s / np.maximum(k, 1), 0.0), k == 0, iterations, tol)
        v[hole] = np.repeat(np.repeat(coarse, 2, 0), 2, 1)[:h, :w][hole]
    else:
        v[hole] = v[~hole].mean() if (~hole).any() else 0.0
    scale = tol * max(np.ptp(v[~hole]) if (~hole).any() else 1.0, 1e-12)
    for _ in range(iterations):
        p = np.pad(v, 1, mode="edge")
        new = (0.25 * (p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:]))[hole]
        change = np.abs(new - v[hole]).max()
        v[hole] = new
        if change < scale:
            break
    return v


def ray_cosines(camera):
    """(H, W) cosine between each pixel-centre ray and the optical axis: z-depth = distance * cosine."""
    py, px = np.mgrid[0:camera.height, 0:camera.width]
    _, d = pixel_rays(camera, px.ravel() + 0.5, py.ravel() + 0.5)
    return (d @ np.asarray(camera.to_world, np.float64)[:3, 2]).reshape(camera.height, camera.width)


def fill_disparity(depth, hole, known=None, ring=8, camera=None, near_tol=0.02):
    """``depth`` (H, W) with the ``hole`` filled: a robust affine fit of the disparity 1 / z on the
    ``ring`` pixels around the hole (``known`` pixels only), plus the harmonic fill of its residual (the
    ring pixels the fit trimmed as outliers, or nearer than the plane by ``near_tol`` of their
    disparity, bound neither). ``depth`` holds z-depths, or with ``camera``
    distances along its pixel-centre rays (converted to z and back); NaN or <= 0 where unknown. Exact
    for a plane seen on every side of the hole."""
    hole = np.asarray(hole, bool)
    known = (~hole if known is None else np.asarray(known, bool) & ~hole) & np.isfinite(depth) & (depth > 0)
    if not hole.any():
        return np.asarray(depth, np.float64).copy()
    if not known.any():
        raise ValueError("no known depth around the hole to fill it from")
    cosine = ray_cosines(camera) if camera is not None else 1.0
    q = np.where(known, 1.0 / np.maximum(depth * cosine, 1e-9), 0.0)
    band = dilate(hole, ring) & known
    if band.sum() < 3:
        band = known
    y, x = np.nonzero(band)
    a = np.stack([x, y, np.ones_like(x)], -1).astype(np.float64)
    b = q[band]
    keep = np.ones(len(b), bool)
    for _ in range(8):  # trim the ring pixels the plane explains worst, and those nearer than it
        coef = np.linalg.lstsq(a[keep], b[keep], rcond=None)[0]
        r = b - a @ coef
        cut = 3.0 * np.median(np.abs(r[keep])) + 1e-12
        good = (np.abs(r) <= cut) & (r <= near_tol * np.abs(a @ coef))
        if (keep & good).sum() < 3 or (good[keep]).all():
            break
        keep &= good
    yy, xx = np.mgrid[0:hole.shape[0], 0:hole.shape[1]]
    plane = coef[0] * xx + coef[1] * yy + coef[2]
    unknown = hole | ~known
    # ring pixels nearer than the plane (an occluder's edge, the object's own haze) bound neither the fit
    # nor the fill: the fill continues the surface behind them
    nearer = b - (a @ coef) > near_tol * np.abs(a @ coef)
    unknown[y[~keep | nearer], x[~keep | nearer]] = True
    residual = harmonic_fill(np.where(unknown, 0.0, q - plane), unknown)
    filled = np.maximum(plane + residual, 1e-6)
    out = np.asarray(depth, np.float64).copy()
    out[hole] = (1.0 / filled / cosine)[hole]
    return out
