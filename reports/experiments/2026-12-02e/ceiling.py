"""#46: how far each family scene's removal margin is bounded by its fields rather than by the removal: the
background layer's PSNR outside the mask (where the fields see everything) against the target (the better of
Telea / Navier-Stokes inside the mask, + 2 dB), from a bench report's family.json.

    python ceiling.py reports/family.json
"""
from family_report import scenes_from_argv

scenes = scenes_from_argv(__doc__, __file__)
print("scene     half   rig       in mask  outside  Telea/NS  target  margin  outside-target")
for name, e in sorted(scenes.items()):
    m = e["strategies"]["guided"]["methods"]
    v, classic = m["volume"], max(m[n]["psnr_mask"] for n in ("telea", "ns") if n in m)
    print(f"{name}  {e['half']:6s} {e['kind']:8s} {v['psnr_mask']:7.2f}  {v['psnr_outside']:7.2f}  {classic:8.2f}  "
          f"{classic + 2:6.2f}  {v['psnr_mask'] - classic:+6.2f}  {v['psnr_outside'] - classic - 2:+6.2f}")
