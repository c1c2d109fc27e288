import json, sys
for p in sys.argv[1:]:
    m = json.load(open(p))["methods"]
    classic = max(m[n]["psnr_mask"] for n in ("telea", "ns"))
    best_c = max(m[n]["consistency_psnr"] for n in m if n not in ("volume", "plate"))
    print(p.split("/")[-2])
    for n, r in m.items():
        print(f"  {n:8s} mask {r['psnr_mask']:.2f} (margin {r['psnr_mask']-classic:+.2f}) unseen {r['psnr_unseen']:.2f} "
              f"cons {r['consistency_psnr']:.2f} (vs best 2D {r['consistency_psnr']-best_c:+.2f}) residue {r['residue']:.3f}")
