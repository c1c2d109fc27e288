"""#46: backgrounds side by side at full size: rows the given held-out views, columns the given folders (each a
`mi_voldis.bench.strategies` output or a run's `previews/`, holding viewNNN_bg.png).

    python side.py OUT.png 8,16 FOLDER...
"""
import os
import sys

from PIL import Image

if len(sys.argv) < 4:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
out, views, folders = sys.argv[1], [int(v) for v in sys.argv[2].split(",")], sys.argv[3:]
if os.path.lexists(out):  # a sheet of its own, never a file already there
    raise SystemExit(f"side.py: {out} exists; give a new file")
ims = [[Image.open(f"{f}/view{v:03d}_bg.png").convert("RGB") for f in folders] for v in views]
w, h = ims[0][0].size
sheet = Image.new("RGB", (w * len(folders), h * len(views)))
for r, row in enumerate(ims):
    for c, im in enumerate(row):
        sheet.paste(im, (c * w, r * h))
sheet.save(out)
