"""mi-voldis: volumetric disentanglement for 3D scene manipulation as Mitsuba 3 plugins.

Implements Benaim et al., "Volumetric Disentanglement for 3D Scene Manipulation" (ECCV 2022):
a full-scene and a background radiance field, sampled at identical points by the ``voldis``
integrator, whose difference is the foreground object.

``import mi_voldis`` selects the ``llvm_ad_rgb`` variant (or ``$MI_VOLDIS_VARIANT``) unless a Mitsuba
variant is already set, and registers the plugins for the active variant:

* ``radiance_field`` (medium): a voxel-grid radiance field, see :mod:`mi_voldis.plugins.radiance_field`;
* ``voldis`` (integrator): aligned-sample mixing of the fields, see :mod:`mi_voldis.plugins.voldis`.

:func:`load_run` opens a fitted run folder for rendering and editing from Python (:mod:`mi_voldis.api`).

Switch variants with :func:`set_variant` (e.g. ``mi_voldis.set_variant("cuda_ad_rgb")``), which also
re-registers the plugins.
"""
import importlib
import os

from . import _llvm

_llvm.configure()

import mitsuba as mi  # noqa: E402

DEFAULT_VARIANT = "llvm_ad_rgb"
PLUGIN_MODULES = ("mi_voldis.plugins.radiance_field", "mi_voldis.plugins.voldis")

__version__ = "0.1.0"


def check_variant(name):
    """Raise ``ValueError`` unless ``name`` is a variant mi-voldis runs on: an AD RGB variant."""
    if "_ad_" not in name or not name.endswith("_rgb"):
        raise ValueError(f"mi_voldis needs a differentiable RGB variant such as 'llvm_ad_rgb' or "
                         f"'cuda_ad_rgb'; got '{name}'.")
    if name not in mi.variants():
        raise ValueError(f"Mitsuba variant '{name}' is not available in this build "
                         f"(available: {', '.join(mi.variants())}).")


def _register_plugins():
    for name in PLUGIN_MODULES:
        module = importlib.import_module(name)
        if getattr(module, "__variant__", None) != mi.variant():
            importlib.reload(module)


def check_device(name):
    """Raise ``ValueError`` when variant ``name`` needs a backend this machine lacks (a CUDA variant
    without an NVIDIA GPU and driver; Mitsuba would raise an ImportError about an uninitialised backend)."""
    import drjit as dr
    if name.startswith("cuda_") and not dr.has_backend(dr.JitBackend.CUDA):
        raise ValueError(f"variant '{name}' (--variant or $MI_VOLDIS_VARIANT): no CUDA device or driver found "
                         f"on this machine; use llvm_ad_rgb")


def set_variant(name):
    """Activate Mitsuba variant ``name`` and register the mi-voldis plugins for it."""
    check_variant(name)
    check_device(name)
    mi.set_variant(name)
    _register_plugins()


if mi.variant() is None:
    set_variant(os.environ.get("MI_VOLDIS_VARIANT") or DEFAULT_VARIANT)
else:
    check_variant(mi.variant())
    _register_plugins()


def load_run(path, dataset=None):
    """A fitted run for rendering and editing from Python (:mod:`mi_voldis.api`)."""
    from .api import load_run as load
    return load(path, dataset)
