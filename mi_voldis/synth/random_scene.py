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

:func:`write_random_scene` writes ``scene.xml``, ``scene.json`` (the rig, as the bundled scenes have)
and ``textures/`` into a folder; :func:`mi_voldis.synth.make.make_dataset` renders it with ground truth.
"""
import json
import os

import numpy as np

from ..io.images import write_png
from . import rigs

TEXTURE = 128  # texture size in pixels


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
        if kind == "textured":
            name = f"textures/t{len(self.textures):02d}.png"
            self.textures[name] = texture(rng)
            return (f'<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" '
                    f'value="{name}"/></texture></bsdf>')
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


def _rig(rng, target, height):
    """Camera rig around ``target``: an orbit or a forward-facing grid (rigs.py), as the JSON rig has it."""
    look = [float(target[0]), float(0.5 * height), float(target[2])]
    if rng.uniform() < 0.5:
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


def random_scene(seed, views=None):
    """(scene XML text, rig dict, {texture path: uint8 image}) of the random scene ``seed``."""
    rng = np.random.default_rng([seed, 7919])
    scene = _Scene(rng)
    base, height, radius = _object(scene)
    cam = _rig(rng, base, height)
    views = views or (40 if cam["type"] == "orbit" else 24)
    # the floor (and for forward rigs the back wall) catches every camera ray. A frustum meets a plane in
    # the quadrilateral of its corner rays (when all of them reach it), so corners bound what must be covered.
    while True:
        probe = rigs.orbit(views, cam["target"], cam["radius"], cam["elevation_deg"], cam["fov_deg"], 16, 12) \
            if cam["type"] == "orbit" else \
            rigs.forward_grid(views, cam["centre"], cam["target"], cam["spread"], cam["fov_deg"], 16, 12)
        ends = _ray_ends(probe, np.zeros(3), np.array([0.0, 1.0, 0.0]))
        if cam["type"] == "forward" or np.isfinite(ends).all():
            break
        cam["elevation_deg"] = [e + 5.0 for e in cam["elevation_deg"]]  # a corner saw the sky: look down more
    centres = np.array([c.to_world[:3, 3] for c in probe])
    if cam["type"] == "forward":
        wall_z = -rng.uniform(0.8, 1.4)
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
                    scene.material("textured"))
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
    xml = "\n    ".join(['<scene version="3.0.0">', '<integrator type="path"><integer name="max_depth" value="6"/>'
                         '</integrator>'] + scene.shapes +
                        [f'<emitter type="point"><point name="position" x="{light[0]:.4g}" y="{light[1]:.4g}" '
                         f'z="{light[2]:.4g}"/><rgb name="intensity" value="{rng.uniform(10, 20):.3g}"/></emitter>',
                         f'<emitter type="constant"><rgb name="radiance" value="{rng.uniform(0.15, 0.35):.3g}"/>'
                         '</emitter>']) + "\n</scene>\n"
    angle = float(rng.uniform(0, 2 * np.pi))
    shift = rng.uniform(0.2, 0.35)
    rig = {"description": f"random scene, seed {seed} (mi_voldis.synth.random_scene)", "object_prefix": "object",
           "cameras": cam, "views": views, "resolution": [160, 120], "spp": 128,
           "moved": {"translate": [float(shift * np.cos(angle)), 0.0, float(shift * np.sin(angle))],
                     "rotate": ["y", float(rng.uniform(20, 60))], "scale": 1.0}}
    if cam["type"] == "orbit":
        rig["aabb"] = [[-floor_half, -0.05, -floor_half], [floor_half, float(height + 0.8), floor_half]]
    return xml, rig, scene.textures


def write_random_scene(seed, folder, views=None):
    """Write the random scene ``seed`` into ``folder`` (scene.xml, scene.json, textures/); returns the
    scene file's path."""
    xml, rig, textures = random_scene(seed, views)
    os.makedirs(os.path.join(folder, "textures"), exist_ok=True)
    for name, image in textures.items():
        write_png(os.path.join(folder, name), image)
    with open(os.path.join(folder, "scene.json"), "w") as f:
        json.dump(rig, f, indent=1)
    path = os.path.join(folder, "scene.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path
