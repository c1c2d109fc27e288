"""Spherical-harmonic degree chosen by the scene: degree 1 only where view dependence pays."""
import numpy as np

from ..field.state import with_sh_degree
from ..metrics import psnr
from ..optim.adam import Adam
from ..optim.loop import optimize
from ..raybank import RayBank
from ..render.views import render_camera
from .fields import fit_integrator
from .problem import FieldFit


def choose_sh_degree(inputs, state, roles):
    """Degree 1 only if view dependence pays. From the fields as they stand (the coarse stage's end), the
    fit goes on for ``sh_trial_steps`` steps at degree 0 and, from the same start, at degree 1 (the
    harmonics zero-extended: the same renders to begin with), density and colour both, at the rates the
    main fit has reached (``lr_final_ratio`` ^ (step / steps)), on most training views; the two are
    compared on the others (every 4th training view, unseen by both trials). Degree 1 when it gains
    ``sh_gain_db`` there.

    Geometry moves with colour in both trials: a degree-0 fit bakes a surface whose colour changes with
    the view into floaters that show each training view its own colour, and a colour-only trial on that
    geometry cannot show what degree 1 would give; with geometry free, degree 1 can explain the colour
    by the view and the floaters, which the withheld views do not agree with, lose their use."""
    cfg, ds = inputs.cfg, inputs.ds
    grey = cfg.sh_color == "grey"
    train = np.asarray(ds.train)
    val, fit = train[::4], np.setdiff1d(train, train[::4])
    if len(fit) == 0:  # one training view: nothing to validate view dependence on
        for r in roles:
            state.fields[r] = with_sh_degree(state.fields[r], 0)
        state.sh_choice = {"degree": 0, "reason": "a single training view: no view to validate degree 1 on"}
        return 0
    fit_bank = RayBank(ds, fit)
    kept = {r: state.fields[r] for r in roles}
    decay = cfg.lr_final_ratio ** (state.step / state.steps_full) if state.steps_full else 1.0
    scores = {}
    for degree in (0, 1):
        for r in roles:
            state.fields[r] = with_sh_degree(kept[r], degree, grey, cfg.sh_view_resolution)
        adam = Adam({}, cfg.adam_beta1, cfg.adam_beta2, warmup=cfg.lr_warmup)
        trial = FieldFit(inputs, state, roles, ("full",), fit_bank, phase=10 + degree, schedule=False, adam=adam,
                         rates=(cfg.lr_density * decay, cfg.lr_color * decay))
        optimize(trial, adam, steps=cfg.sh_trial_steps, final_ratio=1.0, desc=f"SH degree {degree} trial",
                 progress=inputs.progress)
        trial.sync_states()
        integ = fit_integrator(inputs, state)
        scores[degree] = float(np.mean([psnr(ds.as_photographed(render_camera(integ, ds.cameras[v], ("full",))["full"]),
                                             ds.images[v]) for v in val]))
    degree = int(scores[1] - scores[0] >= cfg.sh_gain_db)
    for r in roles:  # back to the main fit's fields, at the chosen degree
        state.fields[r] = with_sh_degree(kept[r], degree, grey, cfg.sh_view_resolution)
    state.sh_choice = {"val_psnr_degree0": scores[0], "val_psnr_degree1": scores[1], "degree": degree,
                       "val_views": val.tolist(), "trial_steps": cfg.sh_trial_steps}
    return degree
