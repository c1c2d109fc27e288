"""Variants of a Mitsuba XML scene for ground truth: without the object, the object's coverage only,
and the object moved. The object is every ``<shape>`` whose id starts with a given prefix.
"""
import copy
import xml.etree.ElementTree as ET

import numpy as np


def parse(path):
    try:
        return ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ValueError(f"{path}: cannot read the scene XML ({e})") from None


def object_shapes(root, prefix):
    return [s for s in root.iter("shape") if s.get("id", "").startswith(prefix)]


def check_object(root, prefix, path):
    if not object_shapes(root, prefix):
        raise ValueError(f"{path}: no <shape> with an id starting with '{prefix}' (the object to disentangle)")


def to_string(root):
    return ET.tostring(root, encoding="unicode")


def without_object(root, prefix):
    """The scene with the object's shapes removed: its shadow and reflections vanish too."""
    out = copy.deepcopy(root)
    for parent in out.iter():
        for child in list(parent):
            if child.tag == "shape" and child.get("id", "").startswith(prefix):
                parent.remove(child)
    return out


def with_integrator(root, kind, **integers):
    """The scene with its integrator replaced by ``<integrator type=kind>`` with integer properties."""
    out = copy.deepcopy(root)
    for child in list(out):
        if child.tag == "integrator":
            out.remove(child)
    integrator = ET.Element("integrator", type=kind)
    for name, value in integers.items():
        ET.SubElement(integrator, "integer", name=name, value=str(value))
    out.insert(0, integrator)
    return out


def coverage_only(root, prefix):
    """Everything black and unlit except the object, which emits 1; rendered with max_depth = 1 this
    gives the object's directly visible pixel coverage (occluders still hide it, mirrors show nothing)."""
    out = with_integrator(root, "path", max_depth=1)
    for parent in out.iter():
        for child in list(parent):
            if child.tag == "emitter":
                parent.remove(child)
    for shape in out.iter("shape"):
        for child in list(shape):
            if child.tag in ("bsdf", "ref", "emitter"):
                shape.remove(child)
        ET.SubElement(ET.SubElement(shape, "bsdf", type="diffuse"), "rgb", name="reflectance", value="0")
        if shape.get("id", "").startswith(prefix):
            ET.SubElement(ET.SubElement(shape, "emitter", type="area"), "rgb", name="radiance", value="1")
    return out


def moved(root, prefix, matrix):
    """The scene with the object's shapes moved by the world-space 4x4 ``matrix``."""
    out = copy.deepcopy(root)
    value = " ".join(f"{v:.9g}" for v in np.asarray(matrix, np.float64).ravel())
    for shape in object_shapes(out, prefix):
        tf = next((t for t in shape.findall("transform") if t.get("name") == "to_world"), None)
        if tf is None:
            tf = ET.SubElement(shape, "transform", name="to_world")
        ET.SubElement(tf, "matrix", value=value)  # appended operations apply last, in world space
    return out
