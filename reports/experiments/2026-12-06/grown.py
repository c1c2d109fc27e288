"""Which captures get a budget grown past the llvm bound (and so stages placed over more than min_steps,
``fit.train.stage_floor``): training pixels, the default minutes, and the bound's.

    python reports/experiments/2026-12-06/grown.py DATASET [DATASET ...]
"""
import sys

import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

from mi_voldis.data import load_dataset  # noqa: E402
from mi_voldis.fit.schedule import auto_minutes  # noqa: E402

for root in sys.argv[1:]:
    ds = load_dataset(root)
    pixels = len(ds.train) * ds.size[0] * ds.size[1] / 1e6
    grown, bound = auto_minutes(ds, "llvm"), auto_minutes(ds, "llvm", grow=False)
    print(f"{root}: {len(ds.train)} training views of {ds.size[0]}x{ds.size[1]}, {pixels:.1f} M pixels: "
          f"{grown:.2f} min ({'grown past' if grown > bound else 'within'} the bound's {bound:.2f})")
