"""Reading images and object masks, with errors that name the file."""
import os

import imageio.v3 as iio
import numpy as np

from .types import DatasetError

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".exr")


def has_alpha(path):
    """True when the image file has an alpha channel (checked on its header only)."""
    try:
        return iio.improps(path).shape[-1] == 4
    except Exception:
        return False


def read_image(path, background=(1.0, 1.0, 1.0)):
    """RGB float32 image in [0, 1]; RGBA is composited over ``background`` (display values)."""
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: image file is missing")
    try:
        img = iio.imread(path)
    except Exception as e:  # imageio raises many types for broken files
        raise DatasetError(f"{path}: unreadable or truncated image ({type(e).__name__}: {e})") from None
    img = _to_float(img, path)
    if img.ndim == 2:
        img = np.repeat(img[..., None], 3, axis=2)
    if img.ndim != 3 or img.shape[2] not in (3, 4):
        raise DatasetError(f"{path}: expected an RGB or RGBA image, got shape {img.shape}")
    if img.shape[2] == 4:
        a = img[..., 3:4]
        img = img[..., :3] * a + np.asarray(background, np.float32) * (1 - a)
    return np.ascontiguousarray(img[..., :3], dtype=np.float32)


def read_mask(path, rule="nonzero"):
    """Boolean object mask. ``rule`` 'nonzero': any value > 0 is the object (SPIn-NeRF labels);
    'white': values above half the range are the object (white = object)."""
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: mask file is missing")
    try:
        m = iio.imread(path)
    except Exception as e:
        raise DatasetError(f"{path}: unreadable or truncated mask ({type(e).__name__}: {e})") from None
    m = _to_float(m, path)
    if m.ndim == 3:
        m = m[..., :3].max(axis=2) if m.shape[2] != 2 else m[..., 0]
    return m > 0 if rule == "nonzero" else m > 0.5


def read_coverage(path):
    """Fractional object coverage in [0, 1] (single channel; EXR or 16-bit PNG)."""
    img = read_image(path)
    return img[..., 0]


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
