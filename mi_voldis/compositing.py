"""Layers a compositor can use: linear light, premultiplied, RGB <= A, and an object layer that rebuilds
the scene over the background.

The integrator's layers are sums over a ray's samples of display-encoded colour (the fields hold sRGB
values, as the photographs do). For EXR they become premultiplied *linear* light: the sRGB curve is
undone on the unpremultiplied colour, alpha is clipped to [0, 1] and colour to [0, A].

The paper's foreground (w_fg = w_full - w_bg, c_fg = c_full - c_bg) is signed: its alpha is negative
where the background lies in front of what the full field shows, and its colour over a tiny alpha
explodes once the sRGB curve is undone. The ``fg`` layer written here is instead defined by the
identity a compositor relies on (Porter-Duff "over", premultiplied, linear light):

    full = fg + (1 - fg.A) bg,

per colour channel and for alpha, with fg.RGB = full - (1 - fg.A) bg. For fg to be a valid
premultiplied colour (0 <= fg.RGB <= fg.A) the matte must be at least, per channel c (difference
matting),

    a_min = max(0, max_c 1 - full_c / bg_c, max_c (full_c - bg_c) / (1 - bg_c)),

and for alpha to hold, fg.A = a_alpha = (full.A - bg.A) / (1 - bg.A) (any matte where bg.A = 1). The
matte is fg.A = min(1, max(a_cover, a_min)), where a_cover is the object's coverage
sum_i max(w_fg,i, 0) (``fg.coverage`` from the integrator) moved just into a_alpha +- tol / (1 - bg.A),
and a_min is taken with a slack tol = :data:`IDENTITY_TOL` on both bounds. The colour identity then
holds at every pixel within tol, and the alpha identity within tol wherever a_min <= a_alpha + tol /
(1 - bg.A). Where it is not, full's colour needs more matte than its alpha gives, and the colour is
kept: fg over bg then has (a_min - a_alpha)(1 - bg.A) more alpha than full. That happens where the
background is partly transparent and mixes with the object along the ray: behind a semi-transparent
edge of the object (the fields compose "over" in display-encoded colour, and undoing the sRGB curve of
a mixture gives less than mixing the undone colours, so full's linear colour falls below fg over bg in
the channels the object lacks), or where background matter lies in front of the object. Where the
fields agree a_min is 0 and the layer is as empty as the coverage. fg.Z is the full field's depth where
the matte is non-zero (there the object is the first surface), 0 elsewhere.

The ``res`` layer (the non-negative task: the light the edit adds, paper Sec. 3.4) is premultiplied
like the others; the main image is the composite plus it.

EXR channel names group into passes as Blender and Nuke read them: a pass is the name before the
last dot, its channels the letter after it (``fg.R fg.G fg.B fg.A``: RGBA pass ``fg``). Depth is a
pass of its own, ``depth.Z`` and ``<layer>_depth.Z``: a depth channel inside a colour pass makes it a
five-channel pass, which Blender's compositor reads as no image at all. Every channel is float32.

Depth channels (``depth.Z``, ``<layer>_depth.Z``) are distances along the camera ray from its origin, in
world units, 0 where the layer is empty.
"""
import numpy as np

from .io.images import srgb_to_linear

LAYERS = ("full", "bg", "fg", "res")
IDENTITY_TOL = 1e-3  # how far (linear light) full may differ from fg over bg: the matte ignores less


def linear_layer(rgb, alpha):
    """Premultiplied display-encoded sums -> premultiplied linear RGB with 0 <= RGB <= A, and A
    clipped to [0, 1]; 0 where A is negligible (below 1e-4)."""
    a = np.clip(np.asarray(alpha, np.float64), 0.0, 1.0)[..., None]
    ok = a > 1e-4
    c = np.where(ok, np.asarray(rgb, np.float64) / np.where(ok, a, 1.0), 0.0)
    lin = srgb_to_linear(np.clip(c, 0.0, 1.0)) * a
    return lin.astype(np.float32), a[..., 0].astype(np.float32)


def _rgb(channels, prefix):
    return np.stack([channels[f"{prefix}{c}"] for c in "RGB"], axis=-1)


def composite_channels(channels):
    """EXR channels for compositing from the integrator's raw channels (:func:`mi_voldis.render.views.
    layer_channels`, :func:`mi_voldis.export.render_channels`): R, G, B, A (the main image), depth.Z,
    and per layer present ``<layer>.R/G/B/A`` and ``<layer>_depth.Z``, all as the module docstring
    states."""
    out = {}
    rgb, a = linear_layer(_rgb(channels, ""), channels["A"])
    out.update({"R": rgb[..., 0], "G": rgb[..., 1], "B": rgb[..., 2], "A": a, "depth.Z": channels["depth.Z"]})
    linear = {}
    for layer in ("full", "bg", "res"):
        if f"{layer}.R" in channels:
            linear[layer] = linear_layer(_rgb(channels, f"{layer}."), channels[f"{layer}.A"])
            out.update(_layer(layer, *linear[layer], channels[f"{layer}.Z"]))
    if "fg.coverage" in channels and "full" in linear and "bg" in linear:
        full, bg = linear["full"][0].astype(np.float64), linear["bg"][0].astype(np.float64)
        full_a, bg_a = linear["full"][1].astype(np.float64), linear["bg"][1].astype(np.float64)
        # the coverage moved just into [a_alpha - s, a_alpha + s], s = tol / (1 - bg.A): alpha within tol
        clear = np.maximum(1.0 - bg_a, 1e-12)
        a_alpha, slack = (full_a - bg_a) / clear, IDENTITY_TOL / clear
        cover = np.clip(channels["fg.coverage"], a_alpha - slack, a_alpha + slack)
        matte = np.clip(np.maximum(cover, minimum_matte(full, bg)), 0.0, 1.0)
        fg = np.clip(full - (1.0 - matte[..., None]) * bg, 0.0, matte[..., None]).astype(np.float32)
        matte = matte.astype(np.float32)
        z = np.where(matte > 0, channels["full.Z"], 0.0).astype(np.float32)
        out.update(_layer("fg", fg, matte, z))
    return out


def minimum_matte(full, bg, tol=IDENTITY_TOL, eps=1e-6):
    """The smallest alpha a for which fg = full - (1 - a) bg satisfies -tol <= fg <= a + tol in every
    channel (premultiplied linear colours, (..., 3)); see the module docstring. The slack ``tol`` keeps
    differences between the fields below it (rounding, fitting noise in dark colours, where the ratio
    full / bg is unstable) out of the matte."""
    with np.errstate(divide="ignore", invalid="ignore"):
        below = np.where(bg > eps, 1.0 - (full + tol) / np.maximum(bg, eps), 0.0)  # fg >= -tol
        above = np.where(bg < 1 - eps, (full - bg - tol) / np.maximum(1.0 - bg, eps), 0.0)  # fg <= a + tol
    return np.maximum(0.0, np.maximum(below, above).max(axis=-1))


def _layer(name, rgb, a, z):
    return {f"{name}.R": rgb[..., 0], f"{name}.G": rgb[..., 1], f"{name}.B": rgb[..., 2], f"{name}.A": a,
            f"{name}_depth.Z": np.asarray(z, np.float32)}


# linear Rec.709 / sRGB primaries and D65 white (x, y): red, green, blue, white
REC709_CHROMATICITIES = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)
CV_FROM_MI = np.diag([-1.0, 1.0, 1.0, 1.0])  # OpenEXR's camera space: +x right, +y up, +z forward


def world_to_camera(camera):
    """OpenEXR's ``worldToCamera`` of a :class:`~mi_voldis.cameras.Camera` as a column-vector 4x4 matrix
    (camera space left-handed: +x right, +y up, +z the viewing direction)."""
    return CV_FROM_MI @ np.linalg.inv(np.asarray(camera.to_world, np.float64))


def world_to_ndc(camera):
    """OpenEXR's ``worldToNDC`` (column-vector form): a world point p maps to (x / w, y / w) in the
    display window's NDC ((0, 0) its top-left corner, (1, 1) its bottom-right; y down)."""
    tan_x, tan_y = camera.tan_scale
    ox, oy = camera.principal
    proj = np.array([[1 / tan_x, 0, 0.5 - ox, 0], [0, -1 / tan_y, 0.5 - oy, 0], [0, 0, 1, 0], [0, 0, 1, 0]])
    return proj @ world_to_camera(camera)


def exr_header(camera=None, command=None):
    """Header attributes of a layered EXR: chromaticities, what the depth channels hold, the software,
    the command, and the camera as Nuke reads it (``worldToCamera``, ``worldToNDC``; OpenEXR stores
    matrices for row vectors, i.e. transposed)."""
    from . import __version__
    header = {"chromaticities": REC709_CHROMATICITIES, "software": f"mi-voldis {__version__}",
              "comments": "colour: linear Rec.709, premultiplied; depth.Z and <layer>_depth.Z: distance "
                          "along the camera ray, world units, 0 where empty; fg = the "
                          "object, full = fg over bg; res = the light a non-negative edit adds"}
    if command:
        header["command"] = command
    if camera is not None:
        header["worldToCamera"] = np.ascontiguousarray(world_to_camera(camera).T, np.float32)
        header["worldToNDC"] = np.ascontiguousarray(world_to_ndc(camera).T, np.float32)  # the binding reads C order
    return header
