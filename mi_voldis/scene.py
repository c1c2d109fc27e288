"""``voldis`` scenes from fields: the one integrator factory and the one scene-file writer that fitting,
tasks and the Python API share.

Integrator properties are a dict as ``mi.load_dict`` takes it (``samples``, ``step_size``,
``composition``, ``mode``, occupancy, scene space, foreground transform; see the ``voldis`` plugin);
:func:`build_integrator` loads fields with them, :func:`write_scene` writes the same fields and
properties as ``.vol`` files and a ``scene.xml`` that ``mi.load_file`` reads back.
"""
import os

import mitsuba as mi
import numpy as np

from .io.scene_xml import save_field, save_grid, sensor_xml
from .io.scene_xml import write_scene as write_scene_xml


def integrator_properties(space, **options):
    """Properties of a ``voldis`` integrator in scene space ``space`` (a :class:`mi_voldis.space.SceneSpace`)
    plus ``options`` (``None`` values left out)."""
    return {**space.integrator_properties(), **{k: v for k, v in options.items() if v is not None}}


def build_integrator(fields, properties):
    """A ``voldis`` integrator over ``fields`` (role -> ``radiance_field`` plugin dict or loaded medium)."""
    return mi.load_dict({"type": "voldis", **properties, **fields}, optimize=False)


def write_scene(folder, fields, properties, cameras=(), name="scene.xml", shared=None, final=None):
    """Write ``fields`` (role -> a field state or a loaded ``radiance_field``) as ``<role>_grid.npz`` (brick
    grids) or ``<role>_density.vol`` / ``<role>_color.vol`` (dense grids) and ``folder/name``: a scene with
    these fields, the integrator ``properties`` and one sensor per camera
    (:class:`mi_voldis.cameras.Camera`). ``shared``: role -> the scene file whose field of that role
    this scene refers to instead of writing it again (by a path relative to ``final``, the folder
    this one becomes, default ``folder``). Returns the scene file's path."""
    bodies, written = {}, {}
    for role, source in (shared or {}).items():
        bodies[role] = shared_body(source, role, final or folder)
    for role, f in ((r, f) for r, f in fields.items() if r not in bodies):
        # a field that is another role's (a background without masks) is written once
        data = getattr(f, "data", None)
        key = id(data) if data is not None else id(f)
        if key not in written:
            written[key] = save_any_field(folder, role, f)
        bodies[role] = written[key]
    sensors = [sensor_xml(c.to_world, c.fov_x, c.width, c.height, 1, c.principal) for c in cameras]
    path = os.path.join(folder, name)
    write_scene_xml(path, bodies, properties, sensors)
    return path


def shared_body(scene_file, role, folder):
    """The ``<medium>`` body of ``role`` in ``scene_file`` with its field files named relative to ``folder``."""
    import xml.etree.ElementTree as ET
    try:
        medium = ET.parse(scene_file).getroot().find(f".//medium[@name='{role}']")
    except (OSError, ET.ParseError) as e:
        raise ValueError(f"{scene_file}: cannot read the scene ({e})") from None
    if medium is None:
        raise ValueError(f"{scene_file}: no field '{role}' to refer to")
    for s in medium.findall("string"):
        if s.get("name") in ("grid", "density", "color"):
            path = os.path.join(os.path.dirname(os.path.abspath(scene_file)), s.get("value"))
            s.set("value", os.path.relpath(path, os.path.abspath(folder)))
    return "".join(ET.tostring(child, encoding="unicode") for child in medium)


def save_any_field(folder, role, field):
    """Write one field's files (brick grid or dense) and return its ``<medium>`` XML body."""
    layout = getattr(field, "layout", None)
    if layout is None:
        return save_field(folder, role, np.array(field.density), np.array(field.color), field.to_world,
                          field.density_scale, field.sh_gate)
    packed = field.data if hasattr(field, "data") and not hasattr(field, "packed") else field.packed
    rows = np.array(packed).reshape(-1, field.width)
    bricks_rows = layout.slots * layout.vertices_per_brick
    view = None if field.view_shape is None else rows[bricks_rows:, 1:4].reshape(*field.view_shape[::-1], 3)
    return save_grid(folder, role, layout, rows[layout.vertices_per_brick:bricks_rows, :field.channels],
                     field.to_world, field.density_scale, field.sh_gate, view)


def load_scene(path, need_fields=True):
    """``mi.load_file(path)`` with errors as one ``ValueError`` naming the file (Mitsuba's XML and plugin
    errors span lines); ``need_fields``: the scene's integrator must be a ``voldis`` with its fields."""
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such scene file")
    try:
        scene = mi.load_file(path)
    except Exception as e:  # noqa: BLE001  (Mitsuba raises RuntimeError for XML, ValueError from plugins)
        text = str(e)
        if "Traceback (most recent call last):" in text:  # a Python plugin raised: its own message, last
            text = [line for line in text.splitlines() if line.strip()][-1].strip()
            text = f"{path}: {text.partition(': ')[2] or text}"
        raise ValueError(text if path in text else f"{path}: {text}") from None
    if need_fields and not getattr(scene.integrator(), "fields", None):
        raise ValueError(f"{path}: its integrator is not a 'voldis' integrator with radiance fields")
    return scene
