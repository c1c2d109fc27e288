"""Lens models of captures (COLMAP, nerfstudio) and their removal: every view becomes a pinhole.

A :class:`Lens` holds OpenCV-style intrinsics (pixels: fx, fy, cx, cy; pixel (i, j) spans [i, i + 1] x
[j, j + 1], as COLMAP, nerfstudio and the Mitsuba camera count) and distortion coefficients. The fields
render through Mitsuba's pinhole camera (square pixels), so a distorted capture, or one with fx != fy,
is resampled once, when it is loaded: the centre (u, v) of a pixel of the pinhole camera
K' = [[f, 0, cx], [0, f, cy]] (f = fx: the same centre and horizontal scale) looks along the
normalised ray (x, y, 1) = ((u - cx) / f, (v - cy) / f, 1), which the lens maps to the source point
(fx x_d + cx, fy y_d + cy) with

    perspective:  r^2 = x^2 + y^2,
                  d = (1 + k1 r^2 + k2 r^4 + k3 r^6 + k8 r^8) / (1 + k4 r^2 + k5 r^4 + k6 r^6),
                  x_d = x d + 2 p1 x y + p2 (r^2 + 2 x^2),  y_d = y d + 2 p2 x y + p1 (r^2 + 2 y^2);
    fisheye:      theta = atan(r),  theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6
                  + k4 theta^8),  x_d = x theta_d / r,  y_d = y theta_d / r.

The perspective map is OpenCV's rational model (COLMAP's FULL_OPENCV: k4..k6 divide) with one more
numerator term: nerfstudio's ``k4`` under OPENCV is that r^8 coefficient ``k8`` (its
``radial_and_tangential_undistort``: 1 + k1 r + k2 r^2 + k3 r^3 + k4 r^4 in its r = x^2 + y^2), not
OpenCV's k4. The fisheye map is OpenCV's (and nerfstudio's OPENCV_FISHEYE). Images are resampled
bilinearly, masks with nearest neighbours (``cv2.remap``); pixels whose source falls outside the photo
repeat its border.

Models by name (COLMAP's and nerfstudio's ``camera_model``): SIMPLE_PINHOLE, PINHOLE (no distortion);
SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV (perspective); OPENCV_FISHEYE, SIMPLE_RADIAL_FISHEYE,
RADIAL_FISHEYE (fisheye). FOV and the thin-prism models are refused.
"""
from dataclasses import dataclass

import cv2
import numpy as np

PERSPECTIVE = ("SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV", "FULL_OPENCV")
FISHEYE = ("OPENCV_FISHEYE", "SIMPLE_RADIAL_FISHEYE", "RADIAL_FISHEYE")
UNSUPPORTED = ("FOV", "THIN_PRISM_FISHEYE", "RAD_TAN_THIN_PRISM_FISHEYE", "EQUIRECTANGULAR")


class LensError(ValueError):
    """A lens model that cannot be turned into a pinhole camera; the caller adds the file."""


@dataclass(frozen=True)
class Lens:
    """Intrinsics in pixels and distortion: ``coeffs`` (k1, k2, p1, p2, k3, k4, k5, k6[, k8]) for
    perspective lenses (OpenCV's order, then the r^8 numerator term), (k1, k2, k3, k4) for fisheye
    lenses."""
    model: str
    fx: float
    fy: float
    cx: float
    cy: float
    coeffs: tuple = ()

    @property
    def fisheye(self):
        return self.model in FISHEYE

    @property
    def distorted(self):
        return self.fisheye or any(c != 0 for c in self.coeffs)

    def scaled(self, s):
        """The same lens for images resized by ``s`` (pixel coordinates of pixel edges, as COLMAP)."""
        return Lens(self.model, self.fx * s, self.fy * s, self.cx * s, self.cy * s, self.coeffs)

    def distort(self, x, y):
        """Normalised image coordinates (x_d, y_d) the lens maps the ray (x, y, 1) to (module docstring)."""
        x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
        r2 = x * x + y * y
        if self.fisheye:
            k1, k2, k3, k4 = (tuple(self.coeffs) + (0.0,) * 4)[:4]
            r = np.sqrt(r2)
            theta = np.arctan(r)
            t2 = theta * theta
            theta_d = theta * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
            s = np.where(r > 1e-12, theta_d / np.maximum(r, 1e-12), 1.0)  # theta_d / r -> 1 on the axis
            return x * s, y * s
        k1, k2, p1, p2, k3, k4, k5, k6, k8 = (tuple(self.coeffs) + (0.0,) * 9)[:9]
        d = (1 + r2 * (k1 + r2 * (k2 + r2 * (k3 + r2 * k8)))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
        return (x * d + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                y * d + 2 * p2 * x * y + p1 * (r2 + 2 * y * y))

    def undistorter(self, width, height):
        """``(fx, cx, cy), resample``: the pinhole camera of the resampled views and a function
        ``resample(image, nearest=False)`` for (H, W[, C]) arrays of this lens's views."""
        f = float(self.fx)
        if not self.distorted and self.fy == self.fx:
            return (f, self.cx, self.cy), _identity
        u, v = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
        xd, yd = self.distort((u - self.cx) / f, (v - self.cy) / f)
        # cv2.remap indexes pixel centres at integers: subtract the half pixel
        mx = (self.fx * xd + self.cx - 0.5).astype(np.float32)
        my = (self.fy * yd + self.cy - 0.5).astype(np.float32)

        def resample(image, nearest=False):
            img = np.asarray(image)
            src = img.astype(np.float32) if img.dtype == bool else img
            out = cv2.remap(src, mx, my, cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE)
            return out.astype(bool) if img.dtype == bool else out
        return (f, self.cx, self.cy), resample


def _identity(image, nearest=False):
    return image


def lens_from_opencv_keys(model, d, nerfstudio=False):
    """Lens of the keys ``camera_model``, fl_x, fl_y, cx, cy, k1..k6, p1, p2 in dict ``d``; with
    ``nerfstudio``, a perspective ``k4`` is nerfstudio's r^8 term (module docstring), else OpenCV's."""
    model = (model or "OPENCV").upper()
    if model in UNSUPPORTED:
        raise LensError(f"camera_model {model} cannot be undistorted to a pinhole camera")
    if model not in PERSPECTIVE + FISHEYE:
        raise LensError(f"unknown camera_model '{model}' (expected one of {', '.join(PERSPECTIVE + FISHEYE)})")
    get = lambda key: float(d.get(key, 0.0))  # noqa: E731
    fx = get("fl_x")
    fy = float(d.get("fl_y", fx))
    if model in FISHEYE:
        coeffs = (get("k1"), get("k2"), get("k3"), get("k4"))
    else:
        coeffs = (get("k1"), get("k2"), get("p1"), get("p2"), get("k3"), 0.0 if nerfstudio else get("k4"),
                  get("k5"), get("k6"), get("k4") if nerfstudio else 0.0)
    return Lens(model, fx, fy, get("cx"), get("cy"), coeffs)


# COLMAP camera models: id -> (name, parameter names); params map to OpenCV's order below.
COLMAP_MODELS = {
    0: ("SIMPLE_PINHOLE", ("f", "cx", "cy")),
    1: ("PINHOLE", ("fx", "fy", "cx", "cy")),
    2: ("SIMPLE_RADIAL", ("f", "cx", "cy", "k1")),
    3: ("RADIAL", ("f", "cx", "cy", "k1", "k2")),
    4: ("OPENCV", ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2")),
    5: ("OPENCV_FISHEYE", ("fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4")),
    6: ("FULL_OPENCV", ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")),
    7: ("FOV", ("fx", "fy", "cx", "cy", "omega")),
    8: ("SIMPLE_RADIAL_FISHEYE", ("f", "cx", "cy", "k1")),
    9: ("RADIAL_FISHEYE", ("f", "cx", "cy", "k1", "k2")),
    10: ("THIN_PRISM_FISHEYE", ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "sx1", "sy1")),
    11: ("RAD_TAN_THIN_PRISM_FISHEYE", ("fx", "fy", "cx", "cy", "k0", "k1", "k2", "k3", "k4", "k5", "p0", "p1",
                                       "s0", "s1", "s2", "s3")),
}
COLMAP_IDS = {name: i for i, (name, _) in COLMAP_MODELS.items()}


def lens_from_colmap(model, params):
    """Lens of a COLMAP camera (model name, parameter list in COLMAP's order)."""
    model_id = COLMAP_IDS.get(model)
    if model_id is None:
        raise LensError(f"unknown COLMAP camera model '{model}'")
    names = COLMAP_MODELS[model_id][1]
    if len(params) != len(names):
        raise LensError(f"COLMAP camera model {model} has {len(names)} parameters, got {len(params)}")
    d = dict(zip(names, map(float, params)))
    if "f" in d:
        d["fx"] = d["fy"] = d["f"]
    keys = {"fl_x": d["fx"], "fl_y": d["fy"], "cx": d["cx"], "cy": d["cy"],
            **{k: v for k, v in d.items() if k[0] in "kp" and k[1:].isdigit()}}
    return lens_from_opencv_keys(model, keys)
