"""A family trial fitted in several --work folders (scenes split between processes), against the default's
committed rows (reports/family.json): every finished scene, then per half the worst margin and the scenes that
meet every target (margin >= 2 dB, consistency margin >= 3 dB, coverage IoU >= 0.9), on the scenes both have.

    python reports/experiments/2026-11-29g/gloss_keep_seen/screen.py WORK [WORK ...]
"""
import json
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.bench.family import scene_row  # noqa: E402


def met(r):
    return r["margin"] >= 2 and r["consistency_margin"] >= 3 and (r["coverage_iou"] or 0) >= 0.9


def main(works, base_path="reports/family.json"):
    with open(base_path) as f:
        base = json.load(f)["scenes"]
    rows = {}
    for work in works:
        for scene in base:
            path = os.path.join(work, "removal", scene, "guided", "metrics.json")
            fit = os.path.join(work, "runs", f"{scene}_0", "metrics.json")
            if os.path.isfile(path) and os.path.isfile(fit):
                with open(path) as f, open(fit) as g:
                    rows[scene] = (scene_row({"strategies": {"guided": json.load(f)}}, "guided"), json.load(g))
    for half in ("check", "tuning"):
        scenes = sorted(s for s in rows if base[s]["half"] == half)
        if not scenes:
            continue
        print(f"## {half} half: {len(scenes)} of 10 scenes fitted")
        old = {s: scene_row(base[s], "guided") for s in scenes}
        for s in scenes:
            new, fit = rows[s]
            o, of = old[s], base[s]["fit"]["metrics"]
            print(f"{s}: full {of['held_out']['psnr']:.2f} -> {fit['held_out']['psnr']:.2f} dB "
                  f"({of['grid']['full'][0]} -> {fit['grid']['full'][0]}), margin {o['margin']:+.2f} -> "
                  f"{new['margin']:+.2f}, consistency {o['consistency_margin']:+.2f} -> "
                  f"{new['consistency_margin']:+.2f}, IoU {o['coverage_iou']:.2f} -> {new['coverage_iou']:.2f}, "
                  "every target "
                  f"{'yes' if met(o) else 'no'} -> {'yes' if met(new) else 'no'}")
        wo = min(scenes, key=lambda s: old[s]["margin"])
        wn = min(scenes, key=lambda s: rows[s][0]["margin"])
        up = sum(rows[s][0]["margin"] > old[s]["margin"] for s in scenes)
        print(f"worst margin {wo} {old[wo]['margin']:+.2f} -> {wn} {rows[wn][0]['margin']:+.2f}; margin up on {up} of "
              f"{len(scenes)}; every target met by {sum(met(old[s]) for s in scenes)} -> "
              f"{sum(met(rows[s][0]) for s in scenes)}; full field up on "
              f"{sum(rows[s][1]['held_out']['psnr'] > base[s]['fit']['metrics']['held_out']['psnr'] for s in scenes)}")


if __name__ == "__main__":
    main(sys.argv[1:])
