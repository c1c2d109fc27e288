"""What a hash-grid field would cost per sample on this backend, beside what the project's grid costs.

Side by side in one process, on the same random points, alternating (so a busy machine slows every row
alike): forward + backward (gradients into the parameters) of
  grid   the project's brick grid lookup (mi_voldis.bricks.trilinear, 4 channels: density + RGB, 256^3),
  hash   drjit.hashgrid.HashGridEncoding (16 levels x 2 features, 2^19 entries a level: Instant-NGP's),
  hash+mlp  the same encoding into a 32 -> 64 -> 64 -> 4 ReLU network (drjit.nn, cooperative vectors).

    python reports/experiments/2026-11-28/hashgrid/throughput.py [--variant llvm_ad_rgb] [--points 131072]

Prints M points / s for each row (best of the repeats) and each row's time over the grid's.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), *[".."] * 4)))

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--points", type=int, default=131072)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    mi.set_variant(args.variant)
    import drjit.nn as nn
    from drjit.hashgrid import HashGridEncoding

    from mi_voldis import bricks
    from mi_voldis.field_state import new_field

    Float = mi.Float
    TensorXf = dr.tensor_t(Float)
    field = new_field([0, 0, 0], [1, 1, 1], 256, 0, -2.0, 1.0)
    grid_data = Float(field.data)
    dr.enable_grad(grid_data)
    enc = HashGridEncoding(Float, 3, n_levels=16, n_features_per_level=2, hashmap_size=2 ** 19,
                           base_resolution=16, per_level_scale=1.38)
    dr.enable_grad(enc.data)
    net = nn.Sequential(nn.Linear(-1, 64, bias=False), nn.ReLU(), nn.Linear(-1, 64, bias=False), nn.ReLU(),
                        nn.Linear(-1, 4, bias=False)).alloc(TensorXf, 32)
    net = nn.pack(net, layout="training")
    weights = net["weights"]  # the packed module's one buffer (its layers are views into it)
    dr.enable_grad(weights)
    rng = dr.rng(seed=1)

    def points():
        p = mi.Point3f(rng.random(Float, args.points), rng.random(Float, args.points), rng.random(Float, args.points))
        dr.eval(p)
        return p

    def loss(values):
        return dr.sum(sum(v * v for v in values))

    def grid_row(p):
        out = bricks.trilinear(grid_data, field.layout, field.width, field.channels, p)
        dr.backward(loss(out))
        return dr.grad(grid_data)

    def hash_row(p):
        dr.backward(loss(enc(p)))
        return dr.grad(enc.data)

    def mlp_row(p):
        out = net(nn.CoopVec(*enc(p)))
        dr.backward(loss(list(out)))
        return dr.grad(enc.data), dr.grad(weights)

    rows = {"grid": grid_row, "hash": hash_row, "hash+mlp": mlp_row}
    best = {k: float("inf") for k in rows}
    for _ in range(args.repeats):
        for name, row in rows.items():
            p = points()
            t0 = time.perf_counter()
            dr.eval(row(p))
            dr.sync_thread()
            best[name] = min(best[name], time.perf_counter() - t0)
            dr.grad(grid_data), dr.clear_grad(grid_data), dr.clear_grad(enc.data), dr.clear_grad(weights)
    print(f"{args.variant}, {args.points} points, forward + backward, best of {args.repeats}:")
    for name, t in best.items():
        print(f"  {name:9s} {args.points / t / 1e6:7.2f} M points/s   {t / best['grid']:6.1f} x the grid's time")


if __name__ == "__main__":
    main()
