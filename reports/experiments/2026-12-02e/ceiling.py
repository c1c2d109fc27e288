"""#46: how far each family scene's removal margin is bounded by its fields rather than by the removal: the
background layer's PSNR outside the mask (where the fields see everything) against the target (the better of
Telea / Navier-Stokes inside the mask, + 2 dB), from a bench report's family.json.

    python ceiling.py reports/family.json
"""
import json
import os
import sys

if len(sys.argv) != 2:
    raise SystemExit(__doc__.strip().splitlines()[-1].strip())
try:
    with open(sys.argv[1]) as f:
        scenes = json.load(f)["scenes"]
except (OSError, ValueError, KeyError) as e:
    raise SystemExit(f"{os.path.basename(__file__)}: {sys.argv[1]}: not a family report ({type(e).__name__}: {e})")
print("scene     half   rig       in mask  outside  Telea/NS  target  margin  outside-target")
for name, e in sorted(scenes.items()):
    m = e["strategies"]["guided"]["methods"]
    v, classic = m["volume"], max(m[n]["psnr_mask"] for n in ("telea", "ns") if n in m)
    print(f"{name}  {e['half']:6s} {e['kind']:8s} {v['psnr_mask']:7.2f}  {v['psnr_outside']:7.2f}  {classic:8.2f}  "
          f"{classic + 2:6.2f}  {v['psnr_mask'] - classic:+6.2f}  {v['psnr_outside'] - classic - 2:+6.2f}")
