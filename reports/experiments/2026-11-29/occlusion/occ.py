"""#46 trial (not in the package): the cosine-weighted share o(x) of a receiver's hemisphere that the object hides,
by marching 64 cosine-distributed directions through an occupancy grid of the object's surface points."""
import numpy as np


def object_grid(points, radius, cells=64):
    lo = points.min(0) - 2 * radius
    hi = points.max(0) + 2 * radius
    voxel = float((hi - lo).max() / cells)
    dims = np.maximum(np.ceil((hi - lo) / voxel).astype(int), 1)
    occ = np.zeros(dims, bool)
    idx = np.clip(np.floor((points - lo) / voxel).astype(int), 0, dims - 1)
    occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    reach = int(np.ceil(radius / voxel))
    for _ in range(reach):  # 6-neighbour dilation
        grown = occ.copy()
        for a in range(3):
            sl = [slice(None)] * 3
            s1, s2 = list(sl), list(sl)
            s1[a], s2[a] = slice(1, None), slice(None, -1)
            grown[tuple(s1)] |= occ[tuple(s2)]
            grown[tuple(s2)] |= occ[tuple(s1)]
        occ = grown
    return occ, lo, voxel


def cosine_directions(k):
    i = np.arange(k) + 0.5
    r = np.sqrt(i / k)
    phi = np.pi * (3 - 5 ** 0.5) * np.arange(k)
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - r * r)], -1)


def occlusion(grid, receivers, normals, k=64, chunk=512):
    occ, lo, voxel = grid
    dims = np.array(occ.shape)
    hi = lo + dims * voxel
    local = cosine_directions(k)
    out = np.full(len(receivers), np.nan)
    ok = np.all(np.isfinite(receivers), 1) & np.all(np.isfinite(normals), 1)
    idx_all = np.flatnonzero(ok)
    nsteps = int(np.ceil(np.linalg.norm(dims) * 2)) + 1
    for s in range(0, len(idx_all), chunk):
        idx = idx_all[s:s + chunk]
        x, n = receivers[idx], normals[idx]
        helper = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
        # orthonormal tangent frame (t, b, n) around each normal
        t = np.cross(n, helper)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        b = np.cross(n, t)
        d = local[None, :, :1] * t[:, None] + local[None, :, 1:2] * b[:, None] + local[None, :, 2:] * n[:, None]
        o = x + voxel * n  # off the surface by a voxel
        with np.errstate(divide="ignore", invalid="ignore"):
            # slab test against the grid's box: entry tn and exit tf along each ray
            t0 = (lo - o[:, None]) / d
            t1 = (hi - o[:, None]) / d
        tn = np.nanmax(np.minimum(t0, t1), -1)
        tf = np.nanmin(np.maximum(t0, t1), -1)
        tn = np.maximum(tn, 0)
        hit = np.zeros(tn.shape, bool)
        live = tf > tn
        steps = np.arange(nsteps) * 0.5 * voxel
        for j in range(0, nsteps, 32):
            ts = tn[..., None] + steps[None, None, j:j + 32]
            inside = live[..., None] & (ts < tf[..., None])
            if not inside.any():
                break
            p = o[:, None, None, :] + ts[..., None] * d[:, :, None, :]
            c = np.floor((p - lo) / voxel).astype(int)
            c = np.clip(c, 0, dims - 1)
            hit |= (occ[c[..., 0], c[..., 1], c[..., 2]] & inside).any(-1)
        out[idx] = hit.mean(1)
    return out
