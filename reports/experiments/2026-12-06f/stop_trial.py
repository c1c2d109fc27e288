"""The default fit with its rays stopped at another transmittance while fitting (a trial of
``mi_voldis.render.quadrature.STOP_TRANSMITTANCE``, 1e-4, which the fitting integrator takes; the fitted scene
and the held-out evaluation keep ``scene_stop_transmittance``, 1e-2). A ray's last sample takes the light left
(``mi_voldis.render.march``), so the stop only changes how many samples a step marches and what the fit sees
past it; the plan counts the samples, so cheaper steps buy more of them.

    python reports/experiments/2026-12-06f/stop_trial.py TRANSMITTANCE DATASET --out RUN [train.py's options]
"""
import os
import sys

sys.path.insert(0, os.getcwd())
from mi_voldis.render import quadrature  # noqa: E402
from voldis_cli.train import entry  # noqa: E402

try:
    stop = float(sys.argv.pop(1))
except (IndexError, ValueError):
    stop = None
if stop is None or not 0 < stop < 1:
    sys.exit("stop_trial.py: the first argument must be a transmittance in (0, 1)")
quadrature.STOP_TRANSMITTANCE = stop
entry()
