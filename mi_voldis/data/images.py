"""Reading images and object masks, with errors that name the file.

Fields are fitted to display-encoded (sRGB) colour, as the photographs are stored. EXR images
hold *linear* light: :func:`read_image` encodes them with the sRGB curve
(after compositing RGBA over the background in linear light), clipping values above 1, and says so
through :func:`is_linear` so that a loader can record the input's colour space.

Read as they are: CMYK (and YCbCr, Lab, HSV) JPEGs are converted to RGB, palette images expanded; an
EXR photo needs colour channels (``R, G, B`` or ``Y``: an EXR holding only ``Z`` is a depth map, not a
photo); alpha is composited over a background colour only where the loader asks for it
(transforms.json datasets, Blender's convention), and an image transparent at every pixel is refused.
Masks are read by their value range (:func:`read_mask`).
"""
import os

import cv2
import imageio.v3 as iio
import numpy as np

from ..io.exr import read_exr
from ..io.images import linear_to_srgb, srgb_to_linear
from .types import DatasetError

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".exr")
LOSSY_EXTENSIONS = (".jpg", ".jpeg")
COLOUR_MODES = ("CMYK", "YCbCr", "LAB", "HSV")  # Pillow modes whose 3 or 4 channels are not R, G, B[, A]


def has_alpha(path):
    """True when the image file has an alpha channel (checked on its header only)."""
    try:
        if is_linear(path):
            return "A" in read_exr(path)
        return iio.improps(path).shape[-1] == 4
    except Exception:
        return False


def alpha_note(paths):
    """The notes of a capture (photos read as their RGB, :func:`read_image` with no background) whose
    images have an alpha channel: one line saying it is left out."""
    with_alpha = [p for p in paths if has_alpha(p)]
    if not with_alpha:
        return []
    return [f"{len(with_alpha)} of {len(paths)} photos have an alpha channel (the first: {with_alpha[0]}); a capture's "
            "photos are read as their RGB, alpha left out (only transforms.json datasets composite RGBA over "
            "their background_color)"]


def is_linear(path):
    """True for files that store linear light (floating-point pixels: EXR)."""
    return path.lower().endswith(".exr")


def _read(path, what, raw=False):
    """Pixels as float32 (H, W) or (H, W, C) in the file's own encoding; ``raw``: as stored (integer
    files keep their integer values)."""
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: {what} file is missing")
    if is_linear(path):
        try:
            channels = read_exr(path)
        except ValueError as e:
            raise DatasetError(str(e)) from None
        return _exr_stack(channels, path, what)
    try:
        mode = iio.immeta(path).get("mode")
        # imageio hands CMYK's four channels over as they are, which would read as RGBA
        img = iio.imread(path, mode="RGB") if mode in COLOUR_MODES else iio.imread(path)
    except Exception as e:  # imageio raises many types for broken files
        raise DatasetError(f"{path}: unreadable or truncated {what} ({type(e).__name__}: {e})") from None
    return np.asarray(img) if raw else _to_float(img, path)


def _exr_stack(channels, path, what):
    """(H, W, C) of an EXR's main image: R, G, B[, A], or Y[, A]; a mask or coverage may also be its
    single channel, whatever its name."""
    for names in (("R", "G", "B", "A"), ("R", "G", "B"), ("Y", "A"), ("Y",)):
        if all(n in channels for n in names):
            return np.stack([channels[n] for n in names], axis=-1).astype(np.float32)
    if len(channels) == 1 and what != "image":
        return next(iter(channels.values())).astype(np.float32)
    raise DatasetError(f"{path}: the EXR {what} has no R, G, B or Y channels (it has {', '.join(sorted(channels))})")


def read_image(path, background=(1.0, 1.0, 1.0)):
    """RGB float32 image in [0, 1], display-encoded; RGBA is composited over ``background`` (display
    values), or its alpha left out when ``background`` is None (a capture's photos: RGB as stored).
    Linear files (EXR) are composited in linear light, then encoded with the sRGB curve. An image whose
    alpha is 0 at every pixel is refused: it holds no picture, only the background colour."""
    img = _read(path, "image")
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=2)
    if img.ndim != 3 or img.shape[2] not in (2, 3, 4):
        raise DatasetError(f"{path}: expected an RGB or RGBA image, got shape {img.shape}")
    if img.shape[2] == 2:  # grey + alpha
        img = np.concatenate([np.repeat(img[..., :1], 3, axis=2), img[..., 1:]], axis=2)
    if not np.all(np.isfinite(img)):
        raise DatasetError(f"{path}: the image has NaN or infinite pixels")
    linear = is_linear(path)
    if img.shape[2] == 4 and not np.any(img[..., 3] > 0):
        raise DatasetError(f"{path}: every pixel is transparent (alpha 0): the image holds no picture")
    if img.shape[2] == 4 and background is not None:
        a = np.clip(img[..., 3:4], 0.0, 1.0)
        bg = np.asarray(background, np.float32)  # a display colour
        if linear:  # EXR colour is premultiplied by alpha
            img = img[..., :3] + srgb_to_linear(bg).astype(np.float32) * (1 - a)
        else:
            img = img[..., :3] * a + bg * (1 - a)
    img = img[..., :3]
    if linear:
        img = linear_to_srgb(img)
    return np.ascontiguousarray(img, dtype=np.float32)


def mask_values(path):
    """(H, W) float mask values in [0, 1] of the file's range (1 = 255 in 8 bits, 65535 in 16, 1.0 in
    EXR), and True when the file is a 0/1 mask (integer pixels whose largest value is 1). A matte stored
    in an alpha channel (RGBA or grey + alpha whose alpha is not constant) is read from the alpha channel;
    colour masks from their brightest channel."""
    m = _read(path, "mask", raw=True)
    if m.ndim == 3:
        if m.shape[2] in (2, 4) and np.ptp(m[..., -1]) > 0:
            m = m[..., -1]
        else:
            m = m[..., :3].max(axis=2) if m.shape[2] != 2 else m[..., 0]
    binary = np.issubdtype(m.dtype, np.integer) and m.max() == 1
    m = m.astype(np.float32) if binary else _to_float(m, path)
    if not np.all(np.isfinite(m)):
        raise DatasetError(f"{path}: the mask has NaN or infinite pixels")
    return m, binary


def read_mask(path, rule="nonzero"):
    """Boolean object mask, read by its value range (:func:`mask_values`). ``rule`` 'nonzero': any value
    > 0 is the object (SPIn-NeRF labels); 'white': values of at least half the range are the object
    (white = object; an EXR's coverage of at least 0.5). A 0/1 mask is the object where it is 1. JPEG
    masks are lossy, their edges ringing with small values: they are thresholded at half the range
    under either rule, so they do not grow. A mask whose values are not 0 somewhere but never reach
    half the range (say, coverage 0.3 everywhere) is refused rather than read as empty."""
    m, binary = mask_values(path)
    if binary or (rule == "nonzero" and not path.lower().endswith(LOSSY_EXTENSIONS)):
        return m > 0
    obj = m >= 0.5
    if not obj.any() and m.max() > 0:
        raise DatasetError(f"{path}: the mask's largest value is {m.max():.3g} of its range 1: no pixel reaches half "
                           "of it, so it marks no object pixel (masks are white, or 1, where the object is)")
    return obj


def read_alpha(path):
    """The alpha channel in [0, 1] of an RGBA or grey + alpha image (H, W), as stored (an EXR's A)."""
    img = _read(path, "image")
    if img.ndim != 3 or img.shape[2] not in (2, 4):
        raise DatasetError(f"{path}: the image has no alpha channel")
    return np.clip(img[..., -1], 0.0, 1.0)


def read_coverage(path):
    """Fractional object coverage in [0, 1] (the first channel; EXR or 16-bit PNG), as stored."""
    img = _read(path, "coverage")
    return img if img.ndim == 2 else img[..., 0]


def _to_float(img, path):
    img = np.asarray(img)
    if img.dtype == np.uint8:
        return img.astype(np.float32) / 255.0
    if img.dtype == np.uint16:
        return img.astype(np.float32) / 65535.0
    if np.issubdtype(img.dtype, np.floating):
        return img.astype(np.float32)
    if img.dtype == bool:
        return img.astype(np.float32)
    raise DatasetError(f"{path}: unsupported pixel type {img.dtype}")


def list_images(directory):
    """Image files directly inside ``directory``, sorted by name."""
    return sorted(f for f in os.listdir(directory)
                  if f.lower().endswith(IMAGE_EXTENSIONS) and os.path.isfile(os.path.join(directory, f)))


def check_sizes(images, paths, what="image"):
    """All arrays must share (H, W); the error names the first file that differs."""
    h, w = images[0].shape[:2]
    for img, path in zip(images, paths):
        if img.shape[:2] != (h, w):
            raise DatasetError(f"{path}: {what} is {img.shape[1]}x{img.shape[0]} but {paths[0]} is {w}x{h}; "
                               f"all {what}s of a set must have one size")


def mask_folder_paths(root, image_paths, factor=None, kind="masks"):
    """Per image, its mask in ``root/<kind>_K/`` (with ``factor`` K > 1, when that folder exists) or
    ``root/<kind>/`` with the same file stem, or None; None when there is no such folder."""
    names = [f"{kind}_{factor}"] if factor and factor > 1 else []
    folder = next((os.path.join(root, d) for d in names + [kind] if os.path.isdir(os.path.join(root, d))), None)
    if folder is None:
        return None
    by_stem = {os.path.splitext(f)[0]: f for f in os.listdir(folder)}
    stems = (os.path.splitext(os.path.basename(p))[0] for p in image_paths)
    return [os.path.join(folder, by_stem[s]) if s in by_stem else None for s in stems]


def read_effects(paths, shape, masks, resize=False):
    """Effect masks (white = where the object changes the rest of the scene: its shadow, its reflection)
    of the views whose entry in ``paths`` is a path, none for the others, outside the object ``masks``;
    None when no view has one. Effect masks without object masks are refused, naming the first file."""
    given = [p for p in paths if p is not None]
    if not given:
        return None
    if masks is None:
        raise DatasetError(f"{given[0]}: effect masks but no object masks to go with them")
    effects, masked = read_masks(paths, "white", shape, [], resize)
    if masked is not None:
        effects[~masked] = False
    return effects & ~masks


def read_masks(paths, rule, shape, notes, resize=False):
    """Object masks of the views whose entry in ``paths`` is a path; a view whose entry is None has no
    mask and gets an all-True one (it trains the full field only; a line in ``notes`` says so).
    Returns (masks (N, H, W) bool, masked (N,) bool or None when every view has a mask), or
    (None, None) when no view has one. ``resize``: masks larger than the images by a whole factor
    (full-resolution masks of downscaled images) are reduced to them (area average > 1/2)."""
    given = [k for k, p in enumerate(paths) if p is not None]
    if not given:
        return None, None
    masks = [read_mask(paths[k], rule) for k in given]
    if resize:
        masks = [_reduce(m, shape) for m in masks]
    check_masks(masks, [paths[k] for k in given], shape)
    out = np.ones((len(paths), *shape), bool)
    out[given] = masks
    if len(given) == len(paths):
        return out, None
    masked = np.zeros(len(paths), bool)
    masked[given] = True
    notes.append(f"{len(paths) - len(given)} of {len(paths)} views have no object mask: they train the full "
                 f"scene only; the background learns from the {len(given)} masked views")
    return out, masked


def _reduce(mask, shape):
    h, w = shape
    if mask.shape == shape or mask.shape[0] % h or mask.shape[1] % w or mask.shape[0] // h != mask.shape[1] // w:
        return mask
    return cv2.resize(mask.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA) > 0.5


def check_masks(masks, paths, images_shape):
    """Masks must match the images' size, show the object somewhere and never cover a whole view."""
    for m, p in zip(masks, paths):
        if m.shape != images_shape:
            raise DatasetError(f"{p}: mask is {m.shape[1]}x{m.shape[0]} but the images are "
                               f"{images_shape[1]}x{images_shape[0]}")
        if m.all():
            raise DatasetError(f"{p}: mask covers every pixel; nothing of the background is visible")
    if not any(m.any() for m in masks):
        raise DatasetError(f"{os.path.dirname(paths[0]) or '.'}: every object mask is empty; "
                           f"the object is visible in no view")
