"""#46 probe: the test suite's tiny tabletop (9 views, 32 x 24, `TINY_FIT`) fitted with each given list of
settings after TINY_FIT, into a new temporary folder; prints each fit's held-out PSNR, the background's in the
mask and the foreground's coverage IoU, and the held-out PSNR of the mean training colour as a flat image.

    python tiny_free_space.py "free_space=false" "free_space=true" "free_space=true steps_full=120" ...
"""
import glob
import json
import os
import sys
import tempfile

import numpy as np
from PIL import Image

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tests"))
from conftest import TINY_FIT  # noqa: E402

from mi_voldis.fit.config import FitConfig  # noqa: E402
from mi_voldis.fit.run import run_fit  # noqa: E402
from mi_voldis.synth.make import make_dataset  # noqa: E402

work = tempfile.mkdtemp(prefix="tiny_free_space_")
data = make_dataset(os.path.join(ROOT, "scenes", "tabletop.xml"), os.path.join(work, "tabletop"), views=9,
                    resolution=(32, 24), spp=4, progress=False)
images = [np.asarray(Image.open(p).convert("RGB"), np.float64) / 255 for p in sorted(glob.glob(f"{data}/images/*"))]
mean = np.mean([im.mean(axis=(0, 1)) for im in images], axis=0)
for v in (0, 8):  # the held-out views at holdout 8
    print(f"flat mean colour, view {v}: {-10 * np.log10(((images[v] - mean) ** 2).mean()):.2f} dB")
for k, extra in enumerate(sys.argv[1:]):
    m = run_fit(data, os.path.join(work, f"run{k}"), FitConfig.from_sources(None, TINY_FIT + extra.split()),
                progress=False)
    print(extra, json.dumps({key: round(m["held_out"][key], 3) for key in ("psnr", "bg_psnr_mask", "fg_coverage_iou")}),
          flush=True)
