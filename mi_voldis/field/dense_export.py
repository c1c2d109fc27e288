"""Dense export: a fitted field resampled onto a regular world-space grid for Mitsuba's ``gridvolume``.

A ``radiance_field`` lives in scene space (world, NDC or contracted; :mod:`mi_voldis.space`), possibly
as sparse bricks, with densities per unit of *scene* length. Mitsuba's ``heterogeneous`` medium wants
world-space grids: for a world region [lo, hi] at N_x x N_y x N_z values this module evaluates, at
each cell centre x (value i at lo + (i + 1/2) (hi - lo) / N, where ``gridvolume``'s texture lookup
places it; its ``to_world`` maps the unit cube onto the region),

    sigma_world(x) = sigma_scene(p) * s(x),   p = from_world(x),
    s(x) = (|J e_x| + |J e_y| + |J e_z|) / 3,  J = dp/dx (central differences, float64),
    albedo(x) = sigmoid(C_0(p))               (the view-independent colour),

where s is the scene length per world length. In world space s = 1; inside the inner cube of a
contracted space s = 1 / R exactly (the space is a scaled copy of the world there); in the outer shell
and in NDC the stretch depends on direction and s is its mean over the axes (an isotropic medium cannot
represent it exactly). Points outside the field's box get sigma = 0.
"""
import os

import drjit as dr
import mitsuba as mi
import numpy as np

from ..io.scene_xml import sensor_xml
from ..io.vol import write_vol
from ..transforms import apply_point
from .activations import sigmoid, softplus


def stretch(space, x, h=1e-4):
    """s(x) of the module docstring for world points ``x`` (n, 3): mean scene length per world length
    along the three world axes."""
    x = np.asarray(x, np.float64)
    h = h * max(1.0, float(np.abs(x).max(initial=0.0)))
    total = np.zeros(len(x))
    for a in range(3):
        e = np.zeros(3)
        e[a] = h
        total += np.linalg.norm(space.from_world_np(x + e) - space.from_world_np(x - e), axis=-1) / (2 * h)
    return total / 3.0


def sample_field(field, space, x):
    """(sigma_world (n,), albedo (n, 3)) of ``field`` (a ``radiance_field``) in ``space`` at world points
    ``x`` (n, 3), NumPy float32."""
    x = np.asarray(x, np.float64)
    p = space.from_world_np(x)
    local = apply_point(field.world_to_local, mi.Point3f(*[mi.Float(np.ascontiguousarray(p[:, a], np.float32))
                                                          for a in range(3)]))
    inside = dr.all((local >= 0.0) & (local <= 1.0))
    with dr.suspend_grad():
        v = field.lookup(local, active=inside)
        sigma = dr.select(inside, field.density_scale * softplus(v[0]), 0.0)
        rgb = [sigmoid(v[c]) for c in (1, 2, 3)]
        dr.eval(sigma, rgb)
    sigma = np.array(sigma, np.float64) * stretch(space, x)
    return sigma.astype(np.float32), np.stack([np.array(c, np.float32) for c in rgb], -1)


SLAB_VERTICES = 1 << 21  # points evaluated at once by export_dense


def export_dense(field, space, lo, hi, resolution, slab_vertices=SLAB_VERTICES):
    """``(sigma_t, albedo)`` arrays (Z, Y, X, 1) and (Z, Y, X, 3) of ``field`` on the world region
    ``lo``..``hi`` at ``resolution`` = (N_x, N_y, N_z) cell centres (module docstring), evaluated in
    z-slabs of about ``slab_vertices`` values."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    nx, ny, nz = (int(n) for n in resolution)
    if min(nx, ny, nz) < 1:
        raise ValueError(f"the export needs at least 1 value per axis, got {resolution}")
    if not np.all(hi > lo):
        raise ValueError(f"the export region needs min < max on every axis, got {lo.tolist()}, {hi.tolist()}")
    axes = [lo[a] + (np.arange(n) + 0.5) * ((hi[a] - lo[a]) / n) for a, n in enumerate((nx, ny, nz))]
    sigma = np.empty((nz, ny, nx, 1), np.float32)
    albedo = np.empty((nz, ny, nx, 3), np.float32)
    per_slab = max(1, slab_vertices // (nx * ny))
    for z0 in range(0, nz, per_slab):
        zs = axes[2][z0:z0 + per_slab]
        zz, yy, xx = np.meshgrid(zs, axes[1], axes[0], indexing="ij")
        s, c = sample_field(field, space, np.stack([xx.ravel(), yy.ravel(), zz.ravel()], -1))
        sigma[z0:z0 + len(zs)] = s.reshape(len(zs), ny, nx, 1)
        albedo[z0:z0 + len(zs)] = c.reshape(len(zs), ny, nx, 3)
    return sigma, albedo


SCENE = """<scene version="3.0.0">
    <!-- {role} field of {source}, resampled by mi_voldis.field.dense_export: sigma_t per world unit,
         albedo = the view-independent colour. A radiance field emits rather than scatters: this
         medium is an approximation for Mitsuba's own volumetric path tracers. A complete scene:
         `mitsuba {role}_gridvolume.xml` or mi.render(mi.load_file(...)) renders the sensor below
         ({camera}). Paths end after {max_depth} scattering events: with albedos near 1 in dense
         media unbounded paths make a render take minutes. -->
    <integrator type="volpath">
        <integer name="max_depth" value="{max_depth}"/>
    </integrator>
    {sensor}
    <emitter type="constant"/>
    <shape type="cube">
        <transform name="to_world">
            <scale value="{half}"/>
            <translate value="{center}"/>
        </transform>
        <bsdf type="null"/>
        <medium type="heterogeneous" name="interior">
            <volume type="gridvolume" name="sigma_t">
                <string name="filename" value="{role}_sigma_t.vol"/>
                <transform name="to_world"> <scale value="{size}"/> <translate value="{lo}"/> </transform>
            </volume>
            <volume type="gridvolume" name="albedo">
                <string name="filename" value="{role}_albedo.vol"/>
                <transform name="to_world"> <scale value="{size}"/> <translate value="{lo}"/> </transform>
            </volume>
            <float name="scale" value="1"/>
        </medium>
    </shape>
</scene>
"""


MAX_DEPTH = 8  # volpath's scattering events per path (module docstring of the written scene)
SPP = 16  # the written sensor's samples per pixel


def source_sensor(scene_file, spp=SPP):
    """The first ``<sensor>`` of ``scene_file`` (a run's or task's scene: the first held-out camera) as
    XML with ``spp`` samples per pixel, or None where it has none."""
    import xml.etree.ElementTree as ET
    try:
        sensor = ET.parse(scene_file).getroot().find("sensor")
    except (OSError, ET.ParseError) as e:
        raise ValueError(f"{scene_file}: cannot read the scene ({e})") from None
    if sensor is None:
        return None
    for count in sensor.iter("integer"):
        if count.get("name") == "sample_count":
            count.set("value", str(spp))
    return ET.tostring(sensor, encoding="unicode").strip()


def region_sensor(lo, hi, spp=SPP, width=160, height=120):
    """A camera that sees the whole region ``lo``..``hi`` from its -z side, a little above (Mitsuba's
    +y up), as XML: for a source scene without sensors."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    fov = 45.0
    distance = radius / np.sin(np.radians(fov) / 2) * 1.05  # the bounding sphere inside the horizontal view
    origin = centre + distance * np.array([0.0, 0.3, -1.0]) / np.linalg.norm([0.0, 0.3, -1.0])
    to_world = mi.ScalarTransform4f().look_at(origin.tolist(), centre.tolist(), [0.0, 1.0, 0.0]).matrix
    return sensor_xml(np.array(to_world, np.float64), fov, width, height, spp)


def write_export(folder, role, sigma, albedo, lo, hi, source="", sensor=None):
    """Write ``<role>_sigma_t.vol``, ``<role>_albedo.vol`` (header box = the region) and
    ``<role>_gridvolume.xml`` (a cube holding a ``heterogeneous`` medium over them, a ``volpath``
    integrator with at most :data:`MAX_DEPTH` scattering events, a constant environment and a sensor)
    into ``folder``; returns the scene file's path. ``sensor``: the sensor's XML (:func:`source_sensor`);
    default :func:`region_sensor`."""
    os.makedirs(folder, exist_ok=True)
    write_vol(os.path.join(folder, f"{role}_sigma_t.vol"), np.clip(sigma, 0.0, None), lo, hi)
    write_vol(os.path.join(folder, f"{role}_albedo.vol"), np.clip(albedo, 0.0, 1.0), lo, hi)
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    path = os.path.join(folder, f"{role}_gridvolume.xml")
    fmt = ", ".join
    with open(path, "w") as f:
        f.write(SCENE.format(role=role, source=source, max_depth=MAX_DEPTH,
                             camera="the source scene's first camera" if sensor else "a view of the whole region",
                             sensor=sensor or region_sensor(lo, hi), half=fmt(f"{v:.9g}" for v in (hi - lo) / 2),
                             center=fmt(f"{v:.9g}" for v in (hi + lo) / 2),
                             size=fmt(f"{v:.9g}" for v in hi - lo), lo=fmt(f"{v:.9g}" for v in lo)))
    return path
