"""Trial 2D inpainter for #46: each row of the hole filled by linear interpolation between the mean colours of the
`band` known pixels just left and right of it (one side: that side's colour), rows with no known pixel left to
Telea. For tall holes before horizontal bands (a statue before lawn, path and bush) it continues each band across
the hole; the bottom of the hole (a pedestal's top) does not bleed upward as it does in Telea, NS and FSR."""
import numpy as np

from mi_voldis.inpaint2d import opencv_inpaint


def lateral_inpaint(image, hole, band=3, smooth=0):
    hole = np.asarray(hole, bool)
    out = np.asarray(image, np.float32).copy()
    h, w = hole.shape
    left_over = np.zeros_like(hole)
    for y in np.nonzero(hole.any(1))[0]:
        row = hole[y]
        x = 0
        while x < w:
            if not row[x]:
                x += 1
                continue
            a = x
            while x < w and row[x]:
                x += 1
            b = x - 1  # hole run [a, b]
            lo = np.arange(max(a - band, 0), a)
            hi = np.arange(b + 1, min(b + 1 + band, w))
            lo, hi = lo[~row[lo]], hi[~row[hi]]
            if not len(lo) and not len(hi):
                left_over[y, a:b + 1] = True
                continue
            cl = out[y, lo].mean(0) if len(lo) else out[y, hi].mean(0)
            ch = out[y, hi].mean(0) if len(hi) else cl
            t = (np.arange(a, b + 1) - (a - 0.5)) / (b - a + 2.0)
            out[y, a:b + 1] = (1 - t)[:, None] * cl + t[:, None] * ch
    if smooth:  # vertical box blur inside the hole: rows' boundary noise becomes streaks
        k = 2 * smooth + 1
        pad = np.pad(out, ((smooth, smooth), (0, 0), (0, 0)), mode="edge")
        blurred = sum(pad[i:i + h] for i in range(k)) / k
        out = np.where(hole[..., None], blurred, out)
    if left_over.any():
        out = opencv_inpaint(out, left_over, "telea")
    return out


def shifted_holes(hole, count=4):
    """Copies of ``hole`` moved sideways and up/down by its own extent plus a margin, where they fall wholly on known
    pixels inside the image: test holes whose truth the photo holds."""
    ys, xs = np.nonzero(hole)
    if not len(ys):
        return []
    h, w = hole.shape
    dy, dx = ys.max() - ys.min() + 1, xs.max() - xs.min() + 1
    out = []
    for sy, sx in ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (-1, -1), (1, -1), (-1, 1)):
        ty, tx = ys + sy * (dy + 4), xs + sx * (dx + 4)
        if ty.min() < 0 or tx.min() < 0 or ty.max() >= h or tx.max() >= w:
            continue
        moved = np.zeros_like(hole)
        moved[ty, tx] = True
        out.append(moved)
        if len(out) == count:
            break
    return out


def select_inpainter(image, hole, methods, exclude=None):
    """The name among ``methods`` (name -> inpainter) whose fills of :func:`shifted_holes` come closest to the photo
    (mean squared error), or None where no test hole fits. ``exclude``: pixels that may not be in a test hole."""
    tests = [t for t in shifted_holes(hole) if exclude is None or not (t & exclude).any()]
    if not tests:
        return None
    err = {k: np.mean([np.mean((f(image, t)[t] - image[t]) ** 2) for t in tests]) for k, f in methods.items()}
    return min(err, key=err.get)


def line_angle(image, hole, ring=6):
    """The direction (radians, image x to y) along which the colours around ``hole`` change least: the
    structure tensor of the grey image summed over a ring of known pixels, its minor eigenvector."""
    from mi_voldis.masks3d import dilate
    grey = np.asarray(image, np.float64).mean(-1)
    gy, gx = np.gradient(grey)
    band = dilate(hole, ring) & ~dilate(hole, 1)
    jxx, jxy, jyy = (gx * gx)[band].sum(), (gx * gy)[band].sum(), (gy * gy)[band].sum()
    theta = 0.5 * np.arctan2(2 * jxy, jxx - jyy)  # the dominant gradient's direction
    coherence = np.hypot(jxx - jyy, 2 * jxy) / max(jxx + jyy, 1e-12)
    return theta + np.pi / 2, coherence


def oriented_inpaint(image, hole, min_coherence=0.0):
    """The lateral fill along the lines of least change around the hole (rows where they are weak)."""
    import cv2

    from mi_voldis.inpaint2d import lateral_inpaint as fill
    angle, coherence = line_angle(image, hole)
    if coherence < min_coherence:
        return fill(image, hole)
    deg = np.degrees(angle)
    h, w = hole.shape
    rot = cv2.getRotationMatrix2D((w / 2, h / 2), deg, 1.0)  # lines turned onto the rows
    cos, sin = abs(rot[0, 0]), abs(rot[0, 1])
    W, H = int(np.ceil(h * sin + w * cos)), int(np.ceil(h * cos + w * sin))
    rot[0, 2] += W / 2 - w / 2
    rot[1, 2] += H / 2 - h / 2
    img = cv2.warpAffine(np.asarray(image, np.float32), rot, (W, H), flags=cv2.INTER_LINEAR)
    valid = cv2.warpAffine(np.ones((h, w), np.uint8), rot, (W, H), flags=cv2.INTER_NEAREST) > 0
    hh = cv2.warpAffine(hole.astype(np.uint8), rot, (W, H), flags=cv2.INTER_NEAREST) > 0
    from mi_voldis.masks3d import dilate
    hh = dilate(hh, 1) | ~valid
    filled = fill(img, hh)
    back = cv2.invertAffineTransform(rot)
    out = cv2.warpAffine(filled, back, (w, h), flags=cv2.INTER_LINEAR)
    return np.where(hole[..., None], out, image).astype(np.float32)
