"""Every hyper-parameter of fitting, named and commented in one place (DVGO / Plenoxels style).

Override from the command line with ``--set name=value`` (repeatable) or a JSON file with
``--config FILE``; the run writes the effective configuration to RUN/config.json.
"""
import dataclasses
import json
from dataclasses import dataclass, field


@dataclass
class FitConfig:
    # ---- schedule: coarse to fine, as data. (step, vertices along the box's longest side)
    resolution_schedule: list = field(default_factory=lambda: [[0, 48], [250, 96], [500, 128]])
    steps_full: int = 800             # steps of the full-scene phase
    steps_bg: int = 150               # steps of the background refit (strategy "refit")
    batch_rays: int = 8192            # random rays per step, drawn across all training views
    batch_tile: int = 1               # > 1: rays in tile x tile pixel tiles. They march 2-3x faster at 128^3 (shared
                                      # cache lines) but train worse per second; tabletop, 2026-11-22, final held-out
                                      # PSNR / fit s: single pixels 29.73 / 68, 2x2 29.26 / 62, 4x4 28.52 / 60,
                                      # 4x4 with 16k rays 29.22 / 80
    step_voxels: float = 0.5          # sample spacing along a ray, in voxels of the current grid
    max_samples: int = 512            # cap on samples per ray

    # ---- optimiser: Adam on raw grid values, exponential decay to lr * lr_final_ratio
    lr_density: float = 0.1           # grids want far larger rates than NeRF MLPs (5e-4)
    lr_color: float = 0.05
    lr_final_ratio: float = 0.1
    adam_beta1: float = 0.9
    adam_beta2: float = 0.99
    lr_warmup: int = 50               # steps of linear learning-rate ramp after every (re)start of Adam

    # ---- initialisation
    density_init_alpha: float = 1e-3  # initial opacity of one sample step (softplus-shifted, like DVGO)
    sh_degree: str = "auto"           # 0, 1, or "auto": degree 1 only if it pays on validation views
    sh_gain_db: float = 2.0           # "auto": validation PSNR degree 1 must gain over degree 0. Tabletop,
                                      # 128 vox, full bench of 2026-11-22 09:30 (since replaced): degree 1
                                      # (auto at 1 dB) 176 s, 1774 MiB, fg coverage IoU 0.73, +1.2 dB held
                                      # out, vs degree 0 65 s, 612 MiB, 0.90; reports/bench.md has a
                                      # degree-1 row (forced from the start)
    sh_trial_steps: int = 100         # "auto": colour-only steps of each degree's trial fit

    # ---- regularisers (weights on per-vertex means; gradients added directly to the grids)
    tv_density: float = 1e-4          # total variation of raw density
    tv_color: float = 1e-5            # total variation of raw colour coefficients
    tv_every: int = 4                 # apply the TV gradient (scaled by this) every k steps: it costs a pass
                                      # over the whole grid, more than the rays at 256^3
    sparsity: float = 1e-5            # L1 on activated density: empty space stays empty

    # ---- modelling only what the scene needs
    tighten_at_step: int = 250        # shrink the box to the space rays end in at this step (0: never)
    tighten_margin: float = 0.04      # margin added around the occupied box, fraction of its size
    occupancy_resolution: int = 96    # occupancy grid cells along the longest side (0: no skipping)
    occupancy_alpha: float = 1e-3     # a cell is empty when no voxel in it reaches this opacity: half the
                                      # initial one, so only space the data carved out is ever skipped
    occupancy_every: int = 100        # steps between occupancy updates (after tightening)
    empty_color_alpha: float = 1e-3   # background colour is reset to black where its voxel opacity is lower

    # ---- background
    bg_strategy: str = "refit"        # "refit": from the full field, hull cleared; "scratch": jointly
    hull_dilation: float = 0.03       # mask dilation for the visual hull, fraction of image diagonal
    hull_min_views: float = 0.9       # a cell is in the hull if inside the dilated mask in this fraction of views
    bg_ray_dilation: float = 0.15     # refit rays come from masks dilated by this fraction of the diagonal
    object_alpha: float = 0.5         # hull voxels this opaque in the full field are the object: emptied in bg

    # ---- bookkeeping
    seed: int = 0
    checkpoint_every: int = 250
    eval_every: int = 250             # held-out PSNR for the PSNR-vs-time log
    eval_views: int = 3               # held-out views rendered for that log
    preview_views: int = 3

    def __post_init__(self):
        for name in ("steps_full", "batch_rays", "batch_tile", "max_samples", "tv_every", "occupancy_every",
                     "sh_trial_steps"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ValueError(f"configuration: {name} must be a whole number >= 1, got {value!r}")
        for name in ("step_voxels", "lr_density", "lr_color"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not value > 0:
                raise ValueError(f"configuration: {name} must be a number > 0, got {value!r}")

    @classmethod
    def from_sources(cls, path=None, overrides=()):
        cfg = cls()
        if path:
            try:
                with open(path) as f:
                    cfg = cfg.replace(**json.load(f))
            except (OSError, ValueError) as e:  # JSON errors are ValueErrors
                raise ValueError(f"{path}: {e}") from e
        for item in overrides:
            if "=" not in item:
                raise ValueError(f"--set expects name=value, got '{item}'")
            name, value = item.split("=", 1)
            cfg = cfg.replace(**{name: _parse(value)})
        return cfg

    def replace(self, **changes):
        names = {f.name for f in dataclasses.fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise ValueError(f"unknown configuration key(s) {', '.join(unknown)}")
        return dataclasses.replace(self, **changes)

    def to_dict(self):
        return dataclasses.asdict(self)


def _parse(value):
    try:
        return json.loads(value)
    except json.JSONDecodeError:
        return value
