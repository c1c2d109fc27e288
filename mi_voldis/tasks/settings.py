"""Every setting of every manipulation task, named, commented and validated (see :mod:`mi_voldis.settings`).

``python scripts/optimize.py --help`` lists them; ``--set name=value`` and ``--config FILE`` override
them; a task writes its effective settings to RUN/<task>/config.json.
"""
import math
from dataclasses import dataclass

import numpy as np

from ..render.mixing import RULES
from ..settings import Settings, setting

# Larger coordinates are a user's slip: the fields are float32 (1e308 turns to inf on the device), and at
# 1e6 world units a float32 position keeps no sub-unit precision
MAX_COORDINATE = 1e6


def _vector_error(value):
    if value is None or (isinstance(value, list) and len(value) == 3 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v) <= MAX_COORDINATE for v in value)):
        return None
    return f"three numbers [x, y, z] of at most {MAX_COORDINATE:g} either way"


def _matrix_error(value):
    """None for a 4x4 world-space affine matrix (nested lists or an array), else what is wrong."""
    if value is None:
        return None
    try:
        m = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        return "a 4x4 matrix of numbers"
    if m.shape != (4, 4) or not np.all(np.abs(m) <= MAX_COORDINATE):
        return f"a 4x4 matrix of numbers of at most {MAX_COORDINATE:g} either way (got shape {m.shape})"
    if not np.allclose(m[3], [0, 0, 0, 1]) or abs(np.linalg.det(m[:3, :3])) < 1e-9:
        return "an invertible affine matrix (last row 0, 0, 0, 1)"
    return None


def _rotation_error(value):
    if value is None:
        return None
    try:
        parse_rotation(value)
    except ValueError as e:
        return str(e)
    return None


# Larger angles are a user's slip: in float32 they have no degrees left (1e308 turns to inf on the way to
# the device, where --scale 1e308 is refused)
MAX_DEGREES = 1e6


def parse_rotation(text):
    """'y:30' -> ('y', 30.0); 'X,Y,Z:DEG' with a vector axis -> ((X, Y, Z), DEG)."""
    what = "AXIS:DEGREES with AXIS x, y, z or X,Y,Z (e.g. 'y:30')"
    try:
        axis, degrees = str(text).split(":")
        degrees = float(degrees)
        axis = axis.strip().lower()
        if axis not in ("x", "y", "z"):
            axis = tuple(float(v) for v in axis.split(","))
            if len(axis) != 3 or not all(math.isfinite(v) for v in axis) or not any(axis):
                raise ValueError
    except ValueError:
        raise ValueError(what) from None
    if not math.isfinite(degrees):
        raise ValueError(what)
    if abs(degrees) > MAX_DEGREES:
        raise ValueError(f"an angle of at most {MAX_DEGREES:g} degrees either way (a turn repeats every 360)")
    return axis, degrees


@dataclass
class TaskSettings(Settings):
    """Shared by every task."""
    steps: int = setting(300, "optimisation steps (optimised tasks)", low=1)
    seed: int = setting(0, "random seed: ray batches and jitter", low=0)
    checkpoint_every: int = setting(100, "steps between checkpoints (optimised tasks)", low=1)
    resume: bool = setting(False, "continue RUN/<task>.partial from its checkpoint")


@dataclass
class RemovalSettings(TaskSettings):
    mask_dilation: float = setting(0.03, "removal is scored inside the masks dilated by this fraction of the "
                                         "image diagonal (as the 2D inpainting it is compared with)", low=0, high=1)


@dataclass
class TransformSettings(TaskSettings):
    scale: float = setting(1.0, "scale of the object about the pivot", low=1e-3, high=1e3)
    rotate: str | None = setting(None, "rotation about the pivot, AXIS:DEGREES (e.g. 'y:30')", check=_rotation_error)
    translate: list = setting([0.0, 0.0, 0.0], "translation [x, y, z] in world units", check=_vector_error)
    pivot: list | None = setting(None, "pivot [x, y, z] in world units (null: the foreground's centre)",
                                 check=_vector_error)
    matrix: list | None = setting(None, "world-space 4x4 matrix moving the object (instead of scale, rotate, "
                                        "translate and pivot)", check=_matrix_error)
    use_dataset_transform: bool = setting(False, "move the object by the dataset's own moved_transform (to "
                                                 "compare with its ground truth) instead of the settings above")
    composition: str = setting("paper", "composition rule of the moved object", choices=tuple(RULES))


@dataclass
class ObjectGridSettings(TaskSettings):
    """Shared by the tasks that optimise a new grid over the object's box on rays near it."""
    resolution: int = setting(48, "new grid's vertices along the object box's longest side", low=2)
    batch_rays: int = setting(4096, "rays per step, near the object", low=1)
    ray_dilation: float = setting(0.1, "rays come from the masks dilated by this fraction of the diagonal",
                                  low=0, high=1)


@dataclass
class CamouflageSettings(ObjectGridSettings):
    composition: str = setting("paper", "composition rule", choices=tuple(RULES))
    lr: float = setting(0.05, "Adam learning rate of raw colour", above=0)


@dataclass
class NonnegSettings(ObjectGridSettings):
    lr_density: float = setting(0.1, "Adam learning rate of the residual's raw density", above=0)
    lr_color: float = setting(0.05, "Adam learning rate of the residual's raw colour", above=0)
    init_alpha: float = setting(1e-3, "initial opacity of the residual per half voxel", above=0, high=0.5)
    init_color: float = setting(-2.0, "initial raw colour of the residual (sigmoid(-2) = 0.12)")


@dataclass
class SemanticSettings(TaskSettings):
    steps: int = setting(100, "optimisation steps", low=1)
    prompt: str = setting("", "the text to steer the foreground's colours towards (required)")
    clip_model: str = setting("", "local Hugging Face CLIP model folder (required; nothing is downloaded)")
    resolution: int = setting(48, "colour-grid vertices along the object box's longest side", low=2)
    lr: float = setting(0.05, "Adam learning rate of raw colour", above=0)
    bg_weight: float = setting(0.5, "weight of the similarity to the background view", low=0)
    l2_weight: float = setting(10.0, "weight of the L2 to the original outside the mask", low=0)

    def check(self):
        if not self.prompt or not self.clip_model:
            raise ValueError("the semantic task needs a prompt and a clip_model (--prompt TEXT --clip-model "
                             "PATH, a local CLIP folder)")


SETTINGS = {"removal": RemovalSettings, "transform": TransformSettings, "camouflage": CamouflageSettings,
            "nonneg": NonnegSettings, "semantic": SemanticSettings}
