"""A removal-family scene as a tilted 360-degree capture: the world turned by ANGLE degrees about a fixed
oblique axis, no aabb (so 'auto' fits it in contracted space), no masks (the full field alone).

    python reports/experiments/2026-11-29c/contract_up/tilted.py SRC DST ANGLE

SRC: a family dataset folder (transforms.json + images/); DST must not exist: it gets transforms.json and
a link to SRC's images.
"""
import json
import os
import sys

import numpy as np


def main(src, dst, angle):
    if os.path.exists(dst):
        sys.exit(f"error: {dst} exists; give a new folder")
    with open(os.path.join(src, "transforms.json")) as f:
        meta = json.load(f)
    a = np.radians(float(angle))
    axis = np.array([1.0, 0.3, 2.0]) / np.linalg.norm([1.0, 0.3, 2.0])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turn = np.eye(4)
    turn[:3, :3] = np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k
    out = {key: value for key, value in meta.items() if key not in ("aabb", "moved_transform", "frames")}
    out["frames"] = [{"file_path": fr["file_path"], "split": fr["split"],
                      "transform_matrix": (turn @ np.array(fr["transform_matrix"])).tolist()}
                     for fr in meta["frames"]]
    os.makedirs(dst)
    os.symlink(os.path.abspath(os.path.join(src, "images")), os.path.join(dst, "images"))
    with open(os.path.join(dst, "transforms.json"), "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main(*sys.argv[1:])
