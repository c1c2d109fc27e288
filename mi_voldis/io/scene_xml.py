"""Write scenes that ``mi.load_file`` reads back (after ``import mi_voldis``): fields, integrator, sensors."""
import os
from xml.sax.saxutils import quoteattr

import numpy as np

from .run_folder import temp_beside
from .vol import write_vol


def _matrix(m):
    return " ".join(f"{v:.9g}" for v in np.asarray(m, dtype=np.float64).ravel())


def _transform(name, m):
    return f'<transform name="{name}"><matrix value="{_matrix(m)}"/></transform>'


def _activation(density_scale, sh_gate):
    gate = '<boolean name="sh_gate" value="true"/>' if sh_gate else ""  # absent: false, as files before it
    return f'<float name="density_scale" value="{density_scale:.9g}"/>{gate}'


def save_field(directory, stem, density, color, to_world, density_scale=1.0, sh_gate=False):
    """Write ``<stem>_density.vol`` and ``<stem>_color.vol`` (raw grids, header bbox = the world box
    when ``to_world`` is axis-aligned) and return the ``<medium>`` XML body for them."""
    to_world = np.asarray(to_world, dtype=np.float64)
    corners = np.array([[x, y, z, 1.0] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) @ to_world.T
    lo, hi = corners[:, :3].min(axis=0), corners[:, :3].max(axis=0)
    names = {}
    for key, values in (("density", density), ("color", color)):
        names[key] = f"{stem}_{key}.vol"
        write_vol(os.path.join(directory, names[key]), values, lo, hi)
    return (f'<string name="density" value={quoteattr(names["density"])}/>'
            f'<string name="color" value={quoteattr(names["color"])}/>'
            f'{_activation(density_scale, sh_gate)}'
            f'{_transform("to_world", to_world)}')


def save_grid(directory, stem, layout, values, to_world, density_scale=1.0, sh_gate=False, view=None):
    """Write ``<stem>_grid.npz``, a brick grid (:mod:`mi_voldis.field.bricks`: its ``table``, the allocated
    bricks' raw ``values`` (bricks * B^3, channels), ``vertices``, the box as ``bbox`` and the view
    lattice ``view`` (Z, Y, X, 3) where given), and return the ``<medium>`` XML body for it. Written to a
    temporary file and renamed."""
    to_world = np.asarray(to_world, dtype=np.float64)
    corners = np.array([[x, y, z, 1.0] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) @ to_world.T
    name = f"{stem}_grid.npz"
    tmp = temp_beside(os.path.join(directory, name), ".npz")
    extra = {} if view is None else {"view": np.asarray(view, np.float32)}
    np.savez(tmp, table=layout.table, data=np.asarray(values, np.float32), vertices=np.array(layout.shape),
             brick=np.array(layout.brick), bbox=np.stack([corners[:, :3].min(axis=0), corners[:, :3].max(axis=0)]),
             **extra)
    os.replace(tmp, os.path.join(directory, name))
    return (f'<string name="grid" value={quoteattr(name)}/>'
            f'{_activation(density_scale, sh_gate)}'
            f'{_transform("to_world", to_world)}')


def sensor_xml(to_world, fov_x, width, height, spp=1, principal=(0.0, 0.0)):
    """A perspective sensor (Mitsuba camera frame: +x left, +y up, +z forward), box-filtered RGB film."""
    return (f'<sensor type="perspective"><float name="fov" value="{fov_x:.9g}"/>'
            f'<string name="fov_axis" value="x"/>'
            f'<float name="principal_point_offset_x" value="{principal[0]:.9g}"/>'
            f'<float name="principal_point_offset_y" value="{principal[1]:.9g}"/>'
            f'<float name="near_clip" value="1e-4"/>'
            f'{_transform("to_world", to_world)}'
            f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>'
            f'<film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/>'
            f'<string name="pixel_format" value="rgb"/><rfilter type="box"/></film></sensor>')


def property_xml(key, value):
    """One integrator property as XML: booleans, integers, floats, strings, and transforms (a
    ``mi.ScalarTransform4f`` or a 4x4 matrix)."""
    if hasattr(value, "matrix") or np.shape(value) == (4, 4):
        return _transform(key, np.array(value.matrix if hasattr(value, "matrix") else value, np.float64))
    kind = "boolean" if isinstance(value, bool) else "integer" if isinstance(value, int) else \
        "float" if isinstance(value, float) else "string"
    text = str(value).lower() if isinstance(value, bool) else f"{value:.9g}" if kind == "float" else str(value)
    return f'<{kind} name="{key}" value={quoteattr(text)}/>'


# What a written scene renders, at its top: Mitsuba's own tools give the integrator's raw sums, which
# differ from the EXR layers the scripts write (XML comments may not hold "--").
ABOUT = """<!-- A mi-voldis scene. Its plugins (radiance_field, voldis) are Python: load it after
     `import mi_voldis` (mi.load_file), not with the `mitsuba` command, which cannot find them;
     the command-line equivalent is `voldis-render SCENE.xml` (scripts/render.py in a checkout).
     mi.render(scene) returns the integrator's raw output, not the EXR layers the scripts write:
     channels 0-2 are the layer `mode` names ('composite': the `composition` rule, 'paper' = the
     paper's Eq. 5) as premultiplied sums of the fields' display-encoded (sRGB) colour, then the
     AOVs A, depth.Z, <layer>.R/G/B/A/Z for full, bg, fg (and res) and fg.coverage, where fg is the
     paper's signed w_fg = w_full - w_bg. mi_voldis.export.render_channels names the channels and
     mi_voldis.compositing.composite_channels turns them into the EXR layers: linear light,
     premultiplied, 0 <= RGB <= A, fg a matte with fg over bg = full. -->"""


def write_scene(path, fields, properties=None, sensors=()):
    """Write a scene with a ``voldis`` integrator, headed by :data:`ABOUT`.

    ``fields``: role -> ``<medium>`` body from :func:`save_field`; ``properties``: integrator
    properties as for ``mi.load_dict`` (see :func:`mi_voldis.scene.build_integrator`); ``sensors``:
    XML strings from :func:`sensor_xml`."""
    body = [property_xml(key, value) for key, value in (properties or {}).items()]
    for role, inner in fields.items():
        body.append(f'<medium type="radiance_field" name="{role}" id="{role}">{inner}</medium>')
    xml = ['<scene version="3.0.0">', ABOUT, '<integrator type="voldis" id="integrator">', *body, '</integrator>',
           *sensors, '</scene>', '']
    tmp = temp_beside(path)
    with open(tmp, "w") as f:
        f.write("\n".join(xml))
    os.replace(tmp, path)
