"""Synthetic datasets with ground truth, rendered from Mitsuba XML scenes (scripts/make_dataset.py)."""
import os

# The bundled scenes (XML, rig JSON, textures): package data of a wheel, and in a checkout the link
# mi_voldis/scenes -> scenes/, so one path serves both.
SCENES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scenes")


def bundled_scene(name):
    """The path of the bundled scene ``name`` ('tabletop', 'room'): its XML beside its rig (``NAME.json``)."""
    return os.path.join(SCENES, name + ".xml")
