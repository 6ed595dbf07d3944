"""How low raw ND (not up to symmetry) can go on a symmetric object, from any touches.

    /usr/bin/python3 models/symmetry_floor.py --data DIR [--end-split test|train]
        [--per-touch SEQ.csv [--method M] [--noise no|...] [--T T]] [OBJECT ...]

A symmetric object maps onto itself under its declared group (object.json "symmetry",
docs/dataset.md), so a touch at c and one at g c press the same shape, and the motions between
touches are the same too: no frame, motion or method can tell the window ending at c from its
image under g. Whatever an estimator answers for those windows, its distance error averaged over
the truth's orbit {g c} is at least the orbit's geometric median's mean distance (the point, on
the object or not, nearest the orbit on average): that over the object's diameter is the
window's floor, a bound on raw ND in expectation over the orbit. An estimator that answers a
point of the surface (the filter's contact always is one) is bound by the same minimum taken over
the surface only (mesh.ply sampled about every 0.5 mm). Beside them, what an estimator exact up to
symmetry scores by picking a copy at random (the mean of |g c - c| over the group).
The windows are `vtloc eval --sequence`'s: ending at the touches of the split with order >= 7.
With --per-touch (`vtloc eval --sequence ... --per-touch` on the same data), the filter's own
raw ND and ND up to symmetry per object beside them.
"""
import argparse
import csv
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from weights_tools import ply  # noqa: E402 (the repository root, put on the path above)


def rotation(axis, angle):
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def group(sym):
    """The group's rotations as engine/sim/symmetry.h reads a declaration (order 0: 360 steps)."""
    n = int(sym.get("order", 1)) or 360
    G = [rotation(sym["axis"], 2 * math.pi * k / n) for k in range(n)]
    if sym.get("flip") is not None:
        F = rotation(sym["flip"], math.pi)
        G += [g @ F for g in G]
    return G


def geometric_median_mean_distance(P, iters=500):
    """min over x of mean |P_i - x| (Weiszfeld's iteration from the centroid)."""
    x = P.mean(0)
    for _ in range(iters):
        d = np.maximum(np.linalg.norm(P - x, axis=1), 1e-12)
        x = (P / d[:, None]).sum(0) / (1 / d).sum()
    return float(np.linalg.norm(P - x, axis=1).mean())


def read_mesh(path):
    """Vertices and triangles of a mesh.ply (weights_tools.ply's reader; errors exit naming the file)."""
    try:
        return ply.read_ply_triangles(path)
    except (ValueError, OSError) as e:
        raise SystemExit(str(e))


def surface_samples(V, T, spacing_mm=0.5, seed=0):
    """Points on the triangles, about one per spacing^2 (at least one per triangle)."""
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    n = np.maximum(1, np.ceil(area / spacing_mm ** 2)).astype(int)
    rng = np.random.default_rng(seed)
    idx = np.repeat(np.arange(len(T)), n)
    u, v = rng.random(len(idx)), rng.random(len(idx))
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    return a[idx] + u[:, None] * (b - a)[idx] + v[:, None] * (c - a)[idx]


def orbit(sym, c):
    point = np.asarray(sym.get("point", [0, 0, 0]), float)
    if sym.get("all"):
        # Every rotation: the orbit is the sphere through c about the point (a fixed sample of it).
        d = np.random.default_rng(1).normal(size=(2000, 3))
        return point + np.linalg.norm(c - point) * d / np.linalg.norm(d, axis=1)[:, None]
    return np.array([point + g @ (c - point) for g in group(sym)])


def window_floor(sym, c, surface=None):
    """(floor, floor on the surface or None, random copy) in mm for a window ending at contact c."""
    c = np.asarray(c, float)
    P = orbit(sym, c)
    on_surface = None
    if surface is not None:
        # The mean distance to the orbit at every surface sample, the orbit in chunks (memory).
        acc = np.zeros(len(surface))
        for i in range(0, len(P), 64):
            acc += np.linalg.norm(surface[:, None, :] - P[None, i:i + 64, :], axis=2).sum(1)
        on_surface = float(acc.min() / len(P))
    return geometric_median_mean_distance(P), on_surface, float(np.linalg.norm(P - c, axis=1).mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--end-split", default="test", choices=["test", "train"])
    ap.add_argument("--per-touch")
    ap.add_argument("--method", default="Geometry")
    ap.add_argument("--noise", default="no")
    ap.add_argument("--T", type=int, default=8)
    ap.add_argument("objects", nargs="*")
    a = ap.parse_args()
    own = {}
    if a.per_touch:
        with open(a.per_touch) as f:
            for r in csv.DictReader(f):
                if r["method"] == a.method and r["odometry_noise"] == a.noise and int(r["T"]) == a.T:
                    own.setdefault(r["object"], []).append((float(r["nd"]), float(r["nd_symmetry"])))
    root = os.path.join(a.data, "objects")
    names = a.objects or sorted(os.listdir(root))
    print("object             windows  floor ND %  on the surface  random copy ND %" + ("  filter ND % (up to symmetry)" if own else ""))
    for name in names:
        with open(os.path.join(root, name, "object.json")) as f:
            obj = json.load(f)
        sym = obj.get("symmetry")
        if not sym:
            continue
        V, T = read_mesh(os.path.join(root, name, "mesh.ply"))
        surface = surface_samples(V, T)
        floors, surf, copies = [], [], []
        with open(os.path.join(root, name, "touches.csv")) as f:
            for r in csv.DictReader(f):
                if r["split"] != a.end_split or int(r["order"]) < 7:
                    continue
                fl, fs, cp = window_floor(sym, [float(r["cx"]), float(r["cy"]), float(r["cz"])], surface)
                floors.append(100 * fl / obj["diameter_mm"])
                surf.append(100 * fs / obj["diameter_mm"])
                copies.append(100 * cp / obj["diameter_mm"])
        if not floors:
            continue
        line = f"{name:18s} {len(floors):7d} {np.mean(floors):11.1f} {np.mean(surf):15.1f} {np.mean(copies):17.1f}"
        if name in own:
            nd = np.mean([v[0] for v in own[name]])
            ndsym = np.mean([v[1] for v in own[name]])
            line += f"  {nd:.1f} ({ndsym:.1f})"
        print(line)


if __name__ == "__main__":
    sys.exit(main())
