"""Random scenes for measuring on scenes nobody tuned for: a Mitsuba XML scene and its rig from a seed.

Every draw comes from ``numpy.random.default_rng(seed)``, so a seed names one scene. A scene holds:

- a floor and (forward-facing rigs) a back wall, each with a procedural texture (checks, stripes or
  smooth noise, random colours), sized from the rig so that every camera ray ends on a surface;
- the object (shapes with ids ``object_*``): one to three parts (spheres, boxes flat to tall) stacked or
  side by side, 0.15 to 0.45 units across, each diffuse, textured-diffuse or glossy (rough plastic);
- two to five other things around it, one of them a mirror (a chrome sphere or panel) with
  probability 0.3, and with probability 0.5 an occluder (a pole) between some cameras and the object;
- a point light casting shadows, above and to a side, plus a dim constant sky;
- a rig: a 360-degree orbit (half the seeds) or a forward-facing grid, looking at the object, and the
  moved-object edit (a translation on the floor and a turn about the vertical).

With a rig ``kind`` (the removal family, :mod:`mi_voldis.synth.family`) the scene is drawn as above and
then made harder from a second stream of the seed, so that what the object hides is what users' photos
hide: the rig is that kind ('orbit', 'forward', 'arc': a hand-held partial orbit, or 'handheld': a
hand-held forward-facing rig; both hand-held paths unevenly spaced, crowded towards one end, the aim
wandering), the floor glossy or patterned, a wall close behind the object (half the forward rigs and
the narrow arcs) and an area light casting soft shadows instead of the point light (half the scenes).

:func:`write_random_scene` writes ``scene.xml``, ``scene.json`` (the rig, as the bundled scenes have)
and ``textures/`` into a folder; :func:`mi_voldis.synth.make.make_dataset` renders it with ground truth.
"""
import json
import os

import numpy as np

from ..io.images import write_png
from . import rigs

TEXTURE = 128  # texture size in pixels
KINDS = ("orbit", "forward", "arc", "handheld")  # the rigs a scene may be asked for


def texture(rng):
    """A (TEXTURE, TEXTURE, 3) uint8 texture: checks, stripes or smooth noise between two random colours."""
    a, b = rng.uniform(0.1, 0.9, 3), rng.uniform(0.1, 0.9, 3)
    y, x = np.mgrid[0:TEXTURE, 0:TEXTURE] / TEXTURE
    kind = rng.integers(3)
    if kind == 0:
        n = rng.integers(4, 12)
        t = ((np.floor(x * n) + np.floor(y * n)) % 2).astype(np.float64)
    elif kind == 1:
        angle, n = rng.uniform(0, np.pi), rng.integers(3, 10)
        t = (np.sin(2 * np.pi * n * (x * np.cos(angle) + y * np.sin(angle))) > 0).astype(np.float64)
    else:
        t = np.zeros((TEXTURE, TEXTURE))
        for f in (2, 4, 8):  # a few octaves of smooth periodic noise
            phase = rng.uniform(0, 2 * np.pi, 2)
            t += np.sin(2 * np.pi * f * x + phase[0]) * np.sin(2 * np.pi * f * y + phase[1]) / f
        t = (t - t.min()) / max(np.ptp(t), 1e-9)
    rgb = a + (b - a) * t[..., None]
    return np.round(rgb * 255).astype(np.uint8)


def _vec(v):
    return ", ".join(f"{float(c):.6g}" for c in v)


class _Scene:
    """Collects the XML of shapes and the textures they use."""

    def __init__(self, rng):
        self.rng, self.shapes, self.textures = rng, [], {}

    def material(self, kind=None):
        rng = self.rng
        kind = kind or rng.choice(["diffuse", "diffuse", "textured", "glossy"])
        colour = rng.uniform(0.05, 0.95, 3)
        if kind in ("textured", "glossy textured"):
            name = f"textures/t{len(self.textures):02d}.png"
            self.textures[name] = texture(rng)
            bitmap = f'<string name="filename" value="{name}"/></texture>'
            if kind == "glossy textured":  # a varnished pattern: highlights over the texture
                return (f'<bsdf type="roughplastic"><texture type="bitmap" name="diffuse_reflectance">{bitmap}'
                        f'<float name="alpha" value="{rng.uniform(0.05, 0.2):.3g}"/></bsdf>')
            return f'<bsdf type="diffuse"><texture type="bitmap" name="reflectance">{bitmap}</bsdf>'
        if kind == "glossy":
            return (f'<bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="{_vec(colour)}"/>'
                    f'<float name="alpha" value="{rng.uniform(0.05, 0.3):.3g}"/></bsdf>')
        if kind == "mirror":
            return '<bsdf type="conductor"><string name="material" value="Ag"/></bsdf>'
        return f'<bsdf type="diffuse"><rgb name="reflectance" value="{_vec(colour)}"/></bsdf>'

    def add(self, ident, kind, centre, size, material, angle=0.0):
        """A sphere (radius ``size[0]``) or a box of half-extents ``size`` at ``centre``, turned by ``angle``
        about y."""
        shape = "sphere" if kind == "sphere" else "cube"
        size = np.full(3, size[0]) if shape == "sphere" else size
        transform = (f'<scale value="{_vec(size)}"/><rotate y="1" angle="{angle:.4g}"/>'
                     f'<translate value="{_vec(centre)}"/>')
        self.shapes.append(f'<shape type="{shape}" id="{ident}"><transform name="to_world">{transform}</transform>'
                           f'{material}</shape>')

    def rectangle(self, ident, transform, material):
        self.shapes.append(f'<shape type="rectangle" id="{ident}"><transform name="to_world">{transform}'
                           f'</transform>{material}</shape>')


def _object(scene):
    """The object's parts; returns (centre of its base, height, radius in the floor plane)."""
    rng = scene.rng
    parts = int(rng.integers(1, 4))
    y, radius, x = 0.0, 0.0, 0.0
    for k in range(parts):
        kind = rng.choice(["sphere", "box", "box"])
        half = rng.uniform(0.08, 0.22)
        size = np.full(3, half) if kind == "sphere" else half * rng.uniform(0.5, 1.5, 3)  # boxes, flat to tall
        beside = k > 0 and rng.uniform() < 0.4
        centre = np.array([x + (size[0] + radius if beside else 0.0), size[1] if beside else y + size[1], 0.0])
        scene.add(f"object_part{k}", kind, centre, size, scene.material(), rng.uniform(0, 90))
        y = max(y, centre[1] + size[1]) if not beside else y
        radius = max(radius, abs(centre[0]) + size.max())
        if beside:
            x = centre[0]
    return np.array([x / 2, 0.0, 0.0]), max(y, 2 * size[1]), radius + 0.05


def _rig(rng, target, height, kind=None):
    """Camera rig around ``target``: an orbit or a forward-facing grid (rigs.py), as the JSON rig has it;
    ``kind`` (:data:`KINDS`) picks which (a hand-held kind: the rig it is drawn from, :func:`_handheld`)."""
    look = [float(target[0]), float(0.5 * height), float(target[2])]
    draw = rng.uniform()
    if (draw < 0.5) if kind is None else kind in ("orbit", "arc"):
        low = rng.uniform(35, 45)
        return {"type": "orbit", "target": look, "radius": float(rng.uniform(2.0, 3.0)),
                "elevation_deg": [float(low), float(low + rng.uniform(10, 25))], "fov_deg": float(rng.uniform(38, 48))}
    distance = rng.uniform(1.8, 2.6)
    azimuth = rng.uniform(-0.5, 0.5)
    centre = [look[0] + distance * np.sin(azimuth), float(look[1] + rng.uniform(0.4, 0.9)),
              look[2] + distance * np.cos(azimuth)]
    return {"type": "forward", "centre": [float(c) for c in centre], "target": look,
            "spread": [float(rng.uniform(0.6, 1.0)), float(rng.uniform(0.3, 0.6))],
            "fov_deg": float(rng.uniform(45, 60))}


class _Handheld:
    """A hand-held path drawn once from ``hard`` (the seed's second stream) and laid out from a rig of
    ``_rig``: for an orbit, an arc of ``span`` degrees about ``facing`` (views crowded towards one end,
    elevations spread over the orbit's range, distances within 10%); for a forward grid, positions across
    its spread crowded to one side, off the plane by up to 0.1. Every camera aims at the target moved
    by a few centimetres. :meth:`rig` lays it out for an elevation range (the floor check raises it)."""

    def __init__(self, hard, cam, views, span=None):
        self.cam, self.span, self.views = cam, span, views
        crowd = hard.uniform(1.0, 2.5)  # u^crowd for u uniform: dense near 0, sparse near 1
        self.along = np.sort(hard.uniform(0, 1, views)) ** crowd
        self.across = hard.uniform(0, 1, views)
        self.off = hard.uniform(-1, 1, views)
        self.facing = float(hard.uniform(0, 360))
        self.aim = hard.uniform(-1, 1, (views, 3)) * (0.04 if cam["type"] == "orbit" else 0.08)

    def rig(self, elevation_deg=None):
        cam, target = self.cam, np.asarray(self.cam["target"], np.float64)
        if cam["type"] == "orbit":
            lo, hi = elevation_deg or cam["elevation_deg"]
            az = np.radians(self.facing + self.span * (self.along - 0.5))
            el = np.radians(lo + (hi - lo) * self.across)
            r = cam["radius"] * (1.0 + 0.1 * self.off)
            pos = target + r[:, None] * np.stack([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)], 1)
            forward = False
        else:
            frame = rigs.look_at(cam["centre"], target)
            x = (self.along - 0.5) * cam["spread"][0]
            y = (self.across - 0.5) * cam["spread"][1]
            pos = np.asarray(cam["centre"]) + x[:, None] * frame[:3, 0] + y[:, None] * frame[:3, 1] \
                + 0.1 * self.off[:, None] * frame[:3, 2]
            forward = True
        return {"type": "path", "forward": forward, "positions": pos.round(6).tolist(),
                "targets": (target + self.aim).round(6).tolist(), "fov_deg": cam["fov_deg"]}


def _cameras(cam, views, width, height):
    if cam["type"] == "orbit":
        return rigs.orbit(views, cam["target"], cam["radius"], cam["elevation_deg"], cam["fov_deg"], width, height)
    if cam["type"] == "forward":
        return rigs.forward_grid(views, cam["centre"], cam["target"], cam["spread"], cam["fov_deg"], width, height)
    return rigs.path(cam["positions"], cam["targets"], cam["fov_deg"], width, height)


def _ray_ends(cameras, plane_point, plane_normal):
    """Points where the corner and edge rays of ``cameras`` meet a plane (rays parallel or away: +inf)."""
    out = []
    for c in cameras:
        tx, ty = c.tan_scale
        for u in (0.0, 0.5, 1.0):
            for v in (0.0, 0.5, 1.0):
                d = c.to_world[:3, :3] @ np.array([(0.5 - u) * tx, (0.5 - v) * ty, 1.0])
                o = c.to_world[:3, 3]
                den = d @ plane_normal
                t = (plane_point - o) @ plane_normal / den if abs(den) > 1e-9 else -1.0
                out.append(o + t * d if t > 0 else np.full(3, np.inf))
    return np.array(out)


def random_scene(seed, views=None, kind=None):
    """(scene XML text, rig dict, {texture path: uint8 image}) of the random scene ``seed``; with ``kind``
    (:data:`KINDS`) the harder scene of the module docstring with that rig."""
    if kind is not None and kind not in KINDS:
        raise ValueError(f"unknown random scene rig kind '{kind}' (expected one of {', '.join(KINDS)})")
    rng = np.random.default_rng([seed, 7919])
    hard = np.random.default_rng([seed, 7919, 1]) if kind else None
    scene = _Scene(rng)
    base, height, radius = _object(scene)
    cam = _rig(rng, base, height, kind)
    orbit = cam["type"] == "orbit"
    # the harder scenes are smaller (128x96, 30 or 20 views) so that twenty fit a benchmark run of hours
    views = views or ((40 if orbit else 24) if hard is None else (30 if orbit else 20))
    # a wall close behind the object: half the forward rigs, and the arcs narrow enough to stay before it
    close = hard is not None and kind != "orbit" and hard.uniform() < 0.5
    path = _Handheld(hard, cam, views, (hard.uniform(100, 160) if close else hard.uniform(160, 300))
                     if kind == "arc" else None) if kind in ("arc", "handheld") else None
    # the floor (and for forward rigs the back wall) catches every camera ray. A frustum meets a plane in
    # the quadrilateral of its corner rays (when all of them reach it), so corners bound what must be covered.
    while True:
        rig_cam = path.rig(cam.get("elevation_deg")) if path else cam
        probe = _cameras(rig_cam, views, 16, 12)
        ends = _ray_ends(probe, np.zeros(3), np.array([0.0, 1.0, 0.0]))
        if not orbit or np.isfinite(ends).all():
            break
        cam["elevation_deg"] = [e + 5.0 for e in cam["elevation_deg"]]  # a corner saw the sky: look down more
    centres = np.array([c.to_world[:3, 3] for c in probe])
    floor_kind = "textured" if hard is None else hard.choice(["textured", "glossy textured", "glossy"])
    if not orbit:
        wall_z = -rng.uniform(0.8, 1.4)
        if close:
            wall_z = -(radius + hard.uniform(0.05, 0.3))
        wall = _ray_ends(probe, np.array([0.0, 0.0, wall_z]), np.array([0.0, 0.0, 1.0]))
        half_w = float(np.max(np.abs(wall[:, 0]))) + 0.3
        top = float(np.max(wall[:, 1])) + 0.3
        scene.rectangle("wall", f'<scale x="{half_w:.4g}" y="{top / 2:.4g}"/><translate x="0" y="{top / 2:.4g}" '
                                f'z="{wall_z:.4g}"/>', scene.material("textured"))
        # a ray that meets the floor before the wall does so between its camera and its wall-plane point
        floor_half = max(half_w, float(np.abs(centres[:, [0, 2]]).max()), -wall_z) + 0.3
    else:
        floor_half = float(np.abs(ends[:, [0, 2]]).max()) + 0.3
    scene.rectangle("floor", f'<rotate x="1" angle="-90"/><scale value="{floor_half:.4g}"/>',
                    scene.material(floor_kind))
    top = float(height + 0.8)  # an orbit's box: the floor and what stands on it
    if close and orbit:  # behind the object, facing the arc's middle, within the box
        facing = np.radians(path.facing)
        normal = np.array([np.sin(facing), 0.0, np.cos(facing)])
        spot = base - (radius + hard.uniform(0.05, 0.3)) * normal
        half_w = min(1.5, 0.9 * floor_half)
        scene.rectangle("wall", f'<scale x="{half_w:.4g}" y="{top / 2 - 0.03:.4g}"/><rotate y="1" '
                                f'angle="{path.facing:.4g}"/><translate x="{spot[0]:.4g}" y="{top / 2:.4g}" '
                                f'z="{spot[2]:.4g}"/>', scene.material("textured"))
    # other things on the floor, clear of the object
    mirror = rng.uniform() < 0.3
    for k in range(int(rng.integers(2, 6))):
        angle, dist = rng.uniform(0, 2 * np.pi), rng.uniform(radius + 0.3, radius + 1.0)
        half = rng.uniform(0.08, 0.25)
        centre = base + np.array([dist * np.cos(angle), half, dist * np.sin(angle)])
        material = scene.material("mirror" if mirror and k == 0 else None)
        scene.add(f"thing{k}", rng.choice(["sphere", "box"]), centre, np.full(3, half), material, rng.uniform(0, 90))
    if rng.uniform() < 0.5:  # a pole between some cameras and the object
        c = probe[int(rng.integers(len(probe)))].to_world[:3, 3]
        towards = np.array([c[0], 0.0, c[2]]) - base
        spot = base + towards * (radius + 0.25) / max(np.linalg.norm(towards), 1e-6)
        spot += np.cross([0.0, 1.0, 0.0], towards / max(np.linalg.norm(towards), 1e-6)) * rng.uniform(-0.15, 0.15)
        tall = height + rng.uniform(0.2, 0.6)
        scene.add("occluder", "box", [spot[0], tall / 2, spot[2]], [0.03, tall / 2, 0.03], scene.material("diffuse"))
    light = [float(rng.uniform(-2, 2)), float(rng.uniform(2.0, 3.5)), float(rng.uniform(-2, 2))]
    intensity = rng.uniform(10, 20)
    if hard is not None and hard.uniform() < 0.5:
        # an area light of side a facing the object: radiance L = I / a^2 keeps the point light's intensity
        # I on its axis, and its shadows soften with a
        side = hard.uniform(0.4, 1.2)
        emitter = (f'<shape type="rectangle" id="light"><transform name="to_world"><scale value="{side / 2:.4g}"/>'
                   f'<lookat origin="{_vec(light)}" target="{_vec(base)}" up="0, 0, 1"/></transform>'
                   f'<emitter type="area"><rgb name="radiance" value="{intensity / side ** 2:.4g}"/></emitter></shape>')
    else:
        emitter = (f'<emitter type="point"><point name="position" x="{light[0]:.4g}" y="{light[1]:.4g}" '
                   f'z="{light[2]:.4g}"/><rgb name="intensity" value="{intensity:.3g}"/></emitter>')
    xml = "\n    ".join(['<scene version="3.0.0">', '<integrator type="path"><integer name="max_depth" value="6"/>'
                         '</integrator>'] + scene.shapes +
                        [emitter, '<emitter type="constant"><rgb name="radiance" '
                         f'value="{rng.uniform(0.15, 0.35):.3g}"/></emitter>']) + "\n</scene>\n"
    angle = float(rng.uniform(0, 2 * np.pi))
    shift = rng.uniform(0.2, 0.35)
    what = f"random scene, seed {seed}" + (f", {kind} rig" if kind else "")
    rig = {"description": f"{what} (mi_voldis.synth.random_scene)", "object_prefix": "object",
           "cameras": rig_cam, "views": views, "resolution": [160, 120] if hard is None else [128, 96], "spp": 128,
           "moved": {"translate": [float(shift * np.cos(angle)), 0.0, float(shift * np.sin(angle))],
                     "rotate": ["y", float(rng.uniform(20, 60))], "scale": 1.0}}
    if orbit:
        rig["aabb"] = [[-floor_half, -0.05, -floor_half], [floor_half, top, floor_half]]
    return xml, rig, scene.textures


def write_random_scene(seed, folder, views=None, kind=None):
    """Write the random scene ``seed`` (``kind``: :func:`random_scene`) into ``folder`` (scene.xml,
    scene.json, textures/); returns the scene file's path."""
    xml, rig, textures = random_scene(seed, views, kind)
    os.makedirs(os.path.join(folder, "textures"), exist_ok=True)
    for name, image in textures.items():
        write_png(os.path.join(folder, name), image)
    with open(os.path.join(folder, "scene.json"), "w") as f:
        json.dump(rig, f, indent=1)
    path = os.path.join(folder, "scene.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path
