"""The removal family's report under today's default, from a merged work folder (``merge_work.py``) whose
tuning scenes hold the default's background row alone: their fits were made again in this checkout and
refitted with the default, the two candidate rows of the tuning half (``guided+hull_color_fill``,
``guided+hole_carve``) were not. So this is ``bench.py --family`` with those rows left out, which reuses every
fit and row and refits none.

    python reports/experiments/2026-12-02/family/report.py MERGED REPORT_DIR [SCENE,SCENE,...]
"""
import os
import sys

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

from mi_voldis.bench import family  # noqa: E402


def main(argv):
    if len(argv) not in (2, 3):
        raise SystemExit(__doc__.strip().splitlines()[-1].strip())
    chosen = argv[2].split(",") if len(argv) == 3 else None
    missing = [s for s in family.scenes(chosen)
               if not os.path.isfile(os.path.join(argv[0], "removal", s, "guided", "metrics.json"))
               or not os.path.isfile(os.path.join(argv[0], "runs", f"{s}_0", "metrics.json"))]
    if missing:  # this script reports what was fitted; it must not start the family's fits
        raise SystemExit(f"report.py: {argv[0]} holds no fit or default row of {', '.join(missing)}")
    family.STRATEGIES["tuning"] = ["guided"]
    family.ROWS = ["guided"]
    results = family.run_family(os.path.abspath(argv[0]), argv[1], chosen)
    print(family.write_family(results, argv[1], "python scripts/bench.py --family"))


if __name__ == "__main__":
    main(sys.argv[1:])
