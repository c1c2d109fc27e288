"""Where the guided background's ghost comes from: a family run's background refitted with some settings,
and for some views (training and held-out) the photo, the colour prior's 2D inpainting, the background
and the true background side by side, with PSNRs in the dilated mask.

    python reports/experiments/2026-11-28/color_fill/ghost_views.py RUN OUT.png VIEWS [--set KEY=VALUE ...]

RUN: a fit kept with --keep-checkpoints (a family run); VIEWS: comma-separated view indices; OUT.png must
not exist. With --set steps_bg=0 the sheet shows how the background starts, before its refit.
"""
import os
import sys

import numpy as np
from refitted import refitted, split_sets


def main(argv):
    sets, plain = split_sets(argv)
    if len(plain) != 3:
        raise SystemExit(__doc__.strip().splitlines()[3].strip())
    run, out = plain[0], plain[1]
    try:
        views = [int(v) for v in plain[2].split(",")]
    except ValueError:
        raise SystemExit(f"error: VIEWS {plain[2]!r}: give view indices separated by commas, e.g. 0,1,8") from None
    if os.path.exists(out):
        raise SystemExit(f"error: {out}: exists; give a new file")
    from mi_voldis.inpaint2d import inpainter
    from mi_voldis.io.images import display_to_uint8, write_png
    from mi_voldis.metrics import dilate, psnr
    from mi_voldis.render.views import render_camera
    ds, cfg, _, _, integrator = refitted(run, sets)
    grow = int(np.ceil(0.01 * np.hypot(*ds.size)))  # the prior's mask growth (mi_voldis.fit.guide)
    scored = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))  # the removal score's
    paint = inpainter(cfg.prior_inpainter)
    rows = []
    if not all(0 <= v < len(ds.cameras) for v in views):
        raise SystemExit(f"error: VIEWS {plain[2]}: {ds.root} has views 0-{len(ds.cameras) - 1}")
    for v in views:
        bg = np.clip(render_camera(integrator, ds.cameras[v], ("bg",))["bg"][0], 0, 1)
        prior = paint(np.clip(ds.images[v], 0, 1), dilate(ds.masks[v], grow))[..., :3]
        truth, region = ds.backgrounds[v][..., :3], dilate(ds.masks[v], scored)
        split = "train" if v in set(int(u) for u in ds.train) else "held out"
        print(f"view {v} ({split}): background {psnr(bg, truth, region):.2f} dB, its 2D prior "
              f"{psnr(prior, truth, region):.2f} dB against the truth in the mask; background against the prior "
              f"{psnr(bg, prior, region):.2f} dB")
        rows.append(np.concatenate([np.clip(ds.images[v][..., :3], 0, 1), prior, bg, truth], 1))
    write_png(out, display_to_uint8(np.concatenate(rows, 0)))


if __name__ == "__main__":
    main(sys.argv[1:])
