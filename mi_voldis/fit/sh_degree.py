"""Spherical-harmonic degree chosen by the scene: degree 1 only where view dependence pays."""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..field_state import FieldState, with_sh_degree
from ..metrics import psnr
from ..optim.adam import Adam
from ..optim.loop import optimize
from ..raybank import RayBank
from ..render.views import render_camera
from .fields import fit_integrator
from .problem import FieldFit


def choose_sh_degree(inputs, state, roles):
    """Degree 1 only if view dependence pays. With the current geometry fixed, colour is fitted from
    scratch at degree 0 and at degree 1 on most training views, and the two are compared on the
    others (every 4th training view, unseen by both colour fits)."""
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
    scores = {}
    for degree in (0, 1):
        for r in roles:
            trial = with_sh_degree(kept[r], degree, grey)
            i = dr.arange(mi.UInt32, dr.width(trial.data))
            channel, empty = i % trial.width, i < trial.layout.vertices_per_brick * trial.width
            colour = (channel > 0) & (channel < trial.channels) & ~empty  # colour fitted from scratch
            state.fields[r] = FieldState(trial.layout, dr.select(colour, 0.0, trial.data), trial.channels,
                                         trial.to_world, trial.density_scale)
        adam = Adam({}, cfg.adam_beta1, cfg.adam_beta2)
        trial = FieldFit(inputs, state, roles, ("full",), fit_bank, phase=10 + degree, schedule=False, adam=adam,
                         rates=(0.0, cfg.lr_color * 2))  # colour only: geometry stays fixed
        optimize(trial, adam, steps=cfg.sh_trial_steps, final_ratio=0.3, desc=f"SH degree {degree} trial",
                 progress=inputs.progress)
        trial.sync_states()
        integ = fit_integrator(inputs, state)
        scores[degree] = float(np.mean([psnr(ds.as_photographed(render_camera(integ, ds.cameras[v], ("full",))["full"]),
                                             ds.images[v]) for v in val]))
    degree = int(scores[1] - scores[0] >= cfg.sh_gain_db)
    for r in roles:  # keep the main fit's colour, at the chosen degree
        state.fields[r] = with_sh_degree(kept[r], degree, grey)
    state.sh_choice = {"val_psnr_degree0": scores[0], "val_psnr_degree1": scores[1], "degree": degree,
                       "val_views": val.tolist()}
    return degree
