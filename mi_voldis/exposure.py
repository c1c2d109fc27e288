"""Per-image colour correction: an affine map of each training photograph's colours (3DGS's and gsplat's
per-image exposure, nerfstudio's appearance embedding reduced to what a capture's auto exposure and white
balance do), fitted with the fields and left out when rendering novel views.

Photograph k is modelled as x' = A_k x + b_k (A_k 3 x 3, b_k 3 x 1) of what the fields render, with
A_k = I + E_k. The E_k, b_k start at 0, are held near it by ``weight * (||E_k||^2 + ||b_k||^2)`` (mean
over images), and are re-centred after every step to a zero mean over the images (:func:`centre`): a
correction shared by every photograph would be a colour of the scene, which the fields must carry,
since novel views are rendered with no correction (the average photograph's).
"""
import drjit as dr
import mitsuba as mi
import numpy as np

WIDTH = 12  # floats per image: E (3 x 3, row-major), then b


def identity(views):
    """Parameters of ``views`` images, every map the identity: a flat Float (views x WIDTH) of zeros."""
    return dr.zeros(mi.Float, views * WIDTH)


def apply(params, view, rgb):
    """A_k rgb + b_k for each ray's image ``view`` (UInt32) and colour ``rgb`` (Color3f)."""
    e = dr.gather(mi.ArrayXf, params, view, shape=(WIDTH, dr.width(view)))
    return mi.Color3f(*[rgb[r] + e[3 * r] * rgb[0] + e[3 * r + 1] * rgb[1] + e[3 * r + 2] * rgb[2] + e[9 + r]
                        for r in range(3)])


def centre(params):
    """The corrections less their mean over the images (zero-mean E_k and b_k)."""
    views = dr.width(params) // WIDTH
    slot = dr.arange(mi.UInt32, views * WIDTH) % WIDTH
    mean = dr.zeros(mi.Float, WIDTH)
    dr.scatter_reduce(dr.ReduceOp.Add, mean, dr.detach(params) * (1.0 / views), slot)
    return dr.detach(params) - dr.gather(mi.Float, mean, slot)


def penalty(params, weight):
    """weight * mean over images of ||E_k||^2 + ||b_k||^2."""
    return weight * dr.sum(dr.square(params)) * (WIDTH / dr.width(params))


def matrices(params):
    """(views, 3, 4) NumPy [A_k | b_k] of the parameters (for reports)."""
    e = np.array(params).reshape(-1, WIDTH)
    out = np.zeros((len(e), 3, 4))
    out[:, :, :3] = np.eye(3) + e[:, :9].reshape(-1, 3, 3)
    out[:, :, 3] = e[:, 9:]
    return out
