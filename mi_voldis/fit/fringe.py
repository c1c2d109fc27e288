"""The object's dark fringe: its contact shadow and its dark soft edge, found beside each mask.

A mask leaves out what the object does to the pixels just beside it. Where it stands on a surface it
blocks the light there: a contact shadow, darkest at the contact and gone within a few pixels, too
narrow and too close to the silhouette for the shadow search (:mod:`mi_voldis.fit.shadow` scores no
pixel within ``MASK_EDGE_PX`` of a mask). Where it meets what lies behind it, a pixel outside the mask
may hold up to half of the object (masks are coverage > 0.5). The masked loss L_bg fits both into the
background, which then keeps a dark outline where the object stood. These pixels join the effect
masks: they leave L_bg and the 2D prior paints them, as it paints the object's shadow. With
``fringe_unseen`` (the default), besides, no view counts as seeing the background through them
(:func:`~mi_voldis.fit.background.never_seen`: the hull vertices seen only there, the object's soft edge
and its outline on the floor, are refilled with the hole instead of kept, their density never thinned:
:func:`~mi_voldis.fit.background.denser`).

The rule, in each masked view: a pixel p outside the mask, within ``width`` pixels of it, is the
object's when, in every colour channel c,

    log(I_c(p) + eps) < log(F_c(p) + eps) - contrast     and     I_c(p) < min_{q in N(p)} I_c(q),

with F the 2D fill (Telea) of the mask grown by ``width``, so from beyond the band, and N(p) the pixels
beyond the band within ``2 width`` of p; and p is not in front of the object (its full-field depth is
not nearer than ``NEARER`` times the object's median depth: an occluder beside the mask is the scene's).
Darker in every channel: a change of material steps some channels up (the object's colour mixed into
an edge pixel, a bright object's own fringe), a loss of light steps them all down. Darker than
everything near it beyond the band: a dark texture (stripes, a pattern, a seam) is darker than the
fill's smooth mean too, but not than its own kind beside the band; a shadow is (without the second
condition a patterned floor's texture was taken on the removal family: reports/notes.md).
"""
import cv2
import numpy as np

from ..inpaint2d import inpainter
from ..metrics import diagonal_pixels, dilate

EPS = 1e-3  # log floor of a channel's value
NEARER = 0.9  # a pixel nearer than this times the object's median depth stands in front of it (guide.py's rule)
REACH = 2  # N(p) reaches this many band widths from p


def dark_fringe(image, mask, width, contrast, depth=None, fill=None):
    """Bool (H, W): the pixels of the object's dark fringe in one view (module docstring). ``image``
    (H, W, 3+) in [0, 1], ``mask`` (H, W) bool, ``width`` the band in pixels, ``contrast`` the log
    step; ``depth`` (H, W) the full field's median depth (NaN where no surface), to leave occluders out;
    ``fill`` the 2D inpainter (default Telea)."""
    rgb = np.clip(np.nan_to_num(np.asarray(image, np.float32)[..., :3]), 0, 1)
    hole = dilate(mask, width)
    band = hole & ~mask
    if not band.any() or hole.all():
        return np.zeros(mask.shape, bool)
    filled = (fill or inpainter("telea"))(rgb, hole)
    darker = np.all(np.log(rgb + EPS) < np.log(np.clip(filled, 0, 1) + EPS) - contrast, axis=-1)
    r = REACH * width
    known = np.where(hole[..., None], np.float32(np.inf), rgb)  # the band and the object are no neighbours
    nearest = cv2.erode(known, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)),
                        borderType=cv2.BORDER_CONSTANT, borderValue=np.inf)
    out = band & darker & np.all(rgb < nearest, axis=-1)
    if depth is not None:
        hit = np.isfinite(depth)
        if (mask & hit).any():
            front = NEARER * float(np.median(depth[mask & hit]))
            out &= ~(hit & (np.nan_to_num(depth, nan=np.inf) < front))
    return out


def find_fringe(ds, width_fraction, contrast, depths=None):
    """The dark fringe (N, H, W) bool of dataset ``ds``'s masked training views (False elsewhere), the
    band ``width_fraction`` of the image diagonal; None when no pixel is found. ``depths``: the full
    field's median depth maps by view (NaN where none), for the views it holds."""
    width = diagonal_pixels(width_fraction, ds.size)
    out = np.zeros(ds.masks.shape, bool)
    fill = inpainter("telea")
    for v in ds.masked_train:
        depth = None if depths is None else depths.get(int(v))
        out[v] = dark_fringe(ds.images[v], ds.masks[v], width, contrast, depth, fill)
    return out if out.any() else None
