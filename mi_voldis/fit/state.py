"""What a fit has made so far, and its checkpoint: the one object that :func:`mi_voldis.fit.train.fit`
changes, saved and restored whole so that a resumed fit continues exactly where it stopped."""
from dataclasses import dataclass, field

import mitsuba as mi
import numpy as np

from ..device import from_numpy
from ..field.bricks import Layout
from ..field.state import FieldState
from ..io.run_folder import Checkpoint
from ..optim.adam import Adam
from ..render.occupancy import Occupancy


@dataclass
class FitState:
    """Field states by role, the scene box they live in, and the bookkeeping of the fit.

    ``phase``/``step``: where the fit stands ('full', 'bg' or 'done', and the step within the phase);
    ``occupancy_on``: empty-space skipping has started; ``hull_points``:
    scene-space points of the object's visual hull (kept occupied while the background is refitted);
    ``log``: one row per step; ``phase_times``: seconds per phase; ``sh_choice``: the trial fits that
    chose the spherical-harmonic degree; ``empty_color_fraction``: background vertices whose colour was
    cleared; ``schedule``, ``steps_full``: the full phase's plan (:mod:`mi_voldis.fit.schedule`) and
    ``plan``: what it was planned from (time budget, resolutions the capture asks for and affords)."""
    lo: np.ndarray
    hi: np.ndarray
    adam: Adam
    fields: dict = field(default_factory=dict)
    phase: str = "full"
    step: int = 0
    occupancy_on: bool = False
    hull_points: np.ndarray | None = None
    log: list = field(default_factory=list)
    phase_times: dict = field(default_factory=dict)
    sh_choice: dict | None = None
    empty_color_fraction: float | None = None
    exposure: object = None  # per training image colour corrections (mi_voldis.exposure), or None
    schedule: list | None = None  # [[step, resolution], ...] of the full phase, once planned
    steps_full: int | None = None  # its steps, once planned
    plan: dict | None = None  # minutes, capture / affordable / final resolution, seconds per coarse step
    occupancy: object = None  # the skipping grid in use (mi_voldis.render.occupancy.Occupancy), or None
    occupancy_phase: int | None = None  # the phase that built it: a resumed phase takes it back unchanged
    strides: tuple = ()  # ((Occupancy, step), ...): the integrator's stride levels built with it (strides)
    prior: dict | None = None  # what the lifted background prior did (mi_voldis.fit.lift.lift_prior)
    prior_keys: np.ndarray | None = None  # lattice keys of the background vertices it changed
    free: np.ndarray | None = None  # the full field's vertices its stage keeps empty (free_space), as made at
    # the stage's start: a resumed stage keeps the same ones
    averages: dict = field(default_factory=dict)  # role -> the moving average of its packed values over the
    # full phase's last stage (mi_voldis.optim.average), until it replaces the field at the phase's end

    META = ("phase", "step", "occupancy_on", "log", "phase_times", "sh_choice", "empty_color_fraction", "schedule",
            "steps_full", "plan", "occupancy_phase", "prior")

    def save(self, path, phase, step):
        """Checkpoint at ``phase``/``step`` (atomically replaces ``path``)."""
        self.phase, self.step = phase, step
        meta = {key: getattr(self, key) for key in self.META}
        meta.update(lo=self.lo.tolist(), hi=self.hi.tolist())
        arrays = {}
        for r, s in self.fields.items():
            arrays[f"{r}/table"] = s.layout.table
            arrays[f"{r}/data"] = np.asarray(s.data)  # a view of Dr.Jit's buffer: written, never copied
            arrays[f"{r}/shape"] = np.array(s.shape)
            arrays[f"{r}/brick"] = np.array(s.layout.brick)
            arrays[f"{r}/channels"] = np.array(s.channels)
            arrays[f"{r}/to_world"] = s.to_world
            arrays[f"{r}/density_scale"] = np.array(s.density_scale)
            arrays[f"{r}/sh_gate"] = np.array(s.sh_gate)
            if s.view_shape is not None:
                arrays[f"{r}/view_shape"] = np.array(s.view_shape)
        for r, a in self.averages.items():
            arrays[f"{r}/average"] = np.asarray(a)
        adam_arrays, meta["adam_t"] = self.adam.state()
        arrays.update({f"adam/{k}": v for k, v in adam_arrays.items()})
        if self.hull_points is not None:
            arrays["hull_points"] = self.hull_points
        if self.prior_keys is not None:
            arrays["prior_keys"] = self.prior_keys
        if self.free is not None:
            arrays["free"] = self.free
        if self.exposure is not None:
            arrays["exposure"] = np.array(self.exposure)
        if self.occupancy is not None:
            o = self.occupancy
            arrays.update(occupancy_arrays("occupancy", o))
        for k, (o, step) in enumerate(self.strides):
            arrays.update(occupancy_arrays(f"strides/{k}", o, step=np.array(step)))
        Checkpoint(path).save(arrays, meta)

    @classmethod
    def load(cls, path, adam):
        """The state saved at ``path`` (None when there is none); ``adam`` receives its moments."""
        loaded = Checkpoint(path).load()
        if loaded is None:
            return None
        arrays, meta = loaded
        fields, averages = {}, {}
        for r in ("full", "bg"):
            if f"{r}/average" in arrays:
                averages[r] = from_numpy(mi.Float, arrays[f"{r}/average"])
            if f"{r}/table" in arrays:
                layout = Layout(tuple(int(v) for v in arrays[f"{r}/shape"]), int(arrays[f"{r}/brick"]),
                                arrays[f"{r}/table"])
                view = arrays.get(f"{r}/view_shape")
                fields[r] = FieldState(layout, from_numpy(mi.Float, arrays[f"{r}/data"]), int(arrays[f"{r}/channels"]),
                                       arrays[f"{r}/to_world"], float(arrays[f"{r}/density_scale"]),
                                       bool(arrays.get(f"{r}/sh_gate", False)),  # absent: saved before the gate
                                       None if view is None else tuple(int(v) for v in view))
        adam.load({k[5:]: v for k, v in arrays.items() if k.startswith("adam/")}, meta["adam_t"])
        exposure = from_numpy(mi.Float, arrays["exposure"]) if "exposure" in arrays else None
        occupancy = occupancy_from(arrays, "occupancy") if "occupancy/cells" in arrays else None
        strides, k = [], 0
        while f"strides/{k}/cells" in arrays:
            strides.append((occupancy_from(arrays, f"strides/{k}"), float(arrays[f"strides/{k}/step"])))
            k += 1
        return cls(np.array(meta["lo"]), np.array(meta["hi"]), adam, fields, hull_points=arrays.get("hull_points"),
                   prior_keys=arrays.get("prior_keys"), free=arrays.get("free"), exposure=exposure, occupancy=occupancy,
                   strides=tuple(strides), averages=averages, **{key: meta.get(key) for key in cls.META})


def occupancy_arrays(prefix, o, **extra):
    """The arrays of a checkpoint holding :class:`Occupancy` ``o`` (and ``extra`` arrays) under ``prefix``."""
    return {f"{prefix}/{k}": v for k, v in
            dict(cells=o.cells, lo=o.lo, hi=o.hi, reach=np.array(o.reach), **extra).items()}


def occupancy_from(arrays, prefix):
    """The :class:`Occupancy` that :func:`occupancy_arrays` saved under ``prefix``."""
    return Occupancy(arrays[f"{prefix}/lo"], arrays[f"{prefix}/hi"], arrays[f"{prefix}/cells"],
                     float(arrays[f"{prefix}/reach"]))
