"""The `guided` row of removal runs (`python -m mi_voldis.bench.strategies RUN guided OUT --refit`):

    python reports/experiments/2026-11-29g/gloss_keep_seen/removal_row.py OUT/metrics.json ...
"""
import json
import sys

for path in sys.argv[1:]:
    with open(path) as f:
        m = json.load(f)["methods"]
    v, best = m["volume"], max(m["telea"]["psnr_mask"], m["ns"]["psnr_mask"])
    print(f"{path}: in the mask {v['psnr_mask']:.3f} dB, margin {v['psnr_mask'] - best:+.2f}, seen "
          f"{v['psnr_seen']:.3f}, unseen {v['psnr_unseen']:.3f}, residue {v['residue']:.4f}, consistency "
          f"{v['consistency_psnr']:.2f}, haze {v['bg_haze_mask']:.4f} / {v['bg_haze_outside']:.4f}")
