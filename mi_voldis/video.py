"""Frame sequences as video: MP4 through imageio's FFmpeg plugin (``pip install .[video]``: imageio-ffmpeg),
else an animated GIF through Pillow (which matplotlib already brings)."""
import os

import imageio.v3 as iio

from .io.run_folder import temp_beside


def has_mp4():
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        return False
    return True


def write_video(stem, frames, fps=24):
    """Write uint8 (H, W, 3) ``frames`` as ``stem.mp4`` (H.264) when imageio-ffmpeg is installed, else
    ``stem.gif``; returns the path. Frames are padded to even sizes for H.264."""
    if has_mp4():
        h, w = frames[0].shape[:2]
        frames = [f[: h - h % 2, : w - w % 2] for f in frames]
        path = stem + ".mp4"
        tmp = temp_beside(path, ".mp4")
        iio.imwrite(tmp, frames, extension=".mp4", fps=fps, codec="libx264", macro_block_size=1)
    else:
        path = stem + ".gif"
        tmp = temp_beside(path, ".gif")
        iio.imwrite(tmp, frames, extension=".gif", duration=1000.0 / fps, loop=0)
    os.replace(tmp, path)
    return path
