"""One bench work folder that links the runs of several: the family screen's folders, each fitted with
``--set sh_degree=1 --set 'sh_color="grey"'``, under one ``--work`` so that ``bench.py --family`` with grey
degree 1 as the default reuses their fits and background refits (``bench.run.finished`` compares the
resolved settings, so a fit made with the settings given by hand is the default's fit once they are the
default) and writes the default's report.

    python reports/experiments/2026-11-29h/grey_default/merge_work.py MERGED W1 W2 ...

MERGED must not exist; it gets runs/, removal/ and data/ (each fit's own dataset) holding symbolic links
only, so nothing of W1... is moved, copied or changed."""
import os
import sys


def main(argv):
    if len(argv) < 2:
        raise SystemExit(__doc__.strip().splitlines()[5].strip())
    merged, sources = os.path.abspath(argv[0]), [os.path.abspath(w) for w in argv[1:]]
    if os.path.lexists(merged):
        raise SystemExit(f"merge_work.py: {merged} exists; give a new folder")
    links = {}
    for w in sources:  # each scene's fit and background rows, from the folder that fitted it
        for sub in ("runs", "removal"):
            folder = os.path.join(w, sub)
            for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
                if name.endswith((".lock", ".partial")):
                    continue
                key = os.path.join(sub, name)
                if key in links:
                    raise SystemExit(f"merge_work.py: {key} is in both {links[key]} and {w}")
                links[key] = w
    for key, w in list(links.items()):  # and the dataset that fit was made from (a folder may hold others)
        if key.startswith("runs" + os.sep) and key.endswith("_0"):
            scene = os.path.basename(key)[:-2]
            links[os.path.join("data", scene)] = w
    for key, w in sorted(links.items()):
        os.makedirs(os.path.join(merged, os.path.dirname(key)), exist_ok=True)
        os.symlink(os.path.join(w, key), os.path.join(merged, key))
    print(f"{merged}: {len(links)} links from {len(sources)} folders")


if __name__ == "__main__":
    main(sys.argv[1:])
