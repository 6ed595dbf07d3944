"""How close an object comes to a turn symmetry it does not declare.

    /usr/bin/python3 models/near_symmetry.py --data DIR [OBJECT ...]

For each object's mesh (DIR/objects/NAME/mesh.ply), two independent area-weighted samples of
N points: the *floor* is their symmetric mean nearest-point distance (what sampling alone
gives), and each half, third and quarter turn about the three principal axes (through the
centroid) is scored by the same distance between the first sample and the turned second.
A turn near the floor is a symmetry the geometry of a few touches cannot see past: the
multi-touch filter's "turned over" ambiguities (docs/results.md, unknown objects). Prints
the best turn per object, its distance, the floor and the object's diameter.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from weights_tools.ply import read_ply_triangles  # noqa: E402 (the repository root, put on the path above)


def sample(V, T, n, rng):
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    tri = rng.choice(len(T), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    return a[tri] + u[:, None] * (b[tri] - a[tri]) + v[:, None] * (c[tri] - a[tri])


def mean_nearest(X, Y, chunk=512):
    """Symmetric mean nearest-point distance between point sets X and Y."""
    def one_way(P, Q):
        out = []
        for i in range(0, len(P), chunk):
            d = ((P[i:i + chunk, None, :] - Q[None, :, :]) ** 2).sum(-1)
            out.append(np.sqrt(d.min(1)))
        return np.concatenate(out).mean()
    return 0.5 * (one_way(X, Y) + one_way(Y, X))


def turn(axis, angle):
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--points", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("objects", nargs="*")
    a = ap.parse_args()
    names = a.objects or sorted(os.listdir(os.path.join(a.data, "objects")))
    print(f"{'object':<16} {'best turn':<22} {'mm':>6} {'floor mm':>9} {'diameter mm':>12} declared")
    for name in names:
        folder = os.path.join(a.data, "objects", name)
        V, T = read_ply_triangles(os.path.join(folder, "mesh.ply"))
        with open(os.path.join(folder, "object.json")) as f:
            info = json.load(f)
        rng = np.random.default_rng(a.seed)
        P, Q = sample(V, T, a.points, rng), sample(V, T, a.points, rng)
        c = np.concatenate([P, Q]).mean(0)
        P, Q = P - c, Q - c
        _, axes = np.linalg.eigh(P.T @ P)
        floor = mean_nearest(P, Q)
        best = None
        for i in range(3):
            for k in (2, 3, 4):
                d = mean_nearest(P, Q @ turn(axes[:, i], 2 * np.pi / k).T)
                if best is None or d < best[0]:
                    best = (d, f"1/{k} turn, axis {i}")
        print(f"{name:<16} {best[1]:<22} {best[0]:6.2f} {floor:9.2f} {info.get('diameter_mm', float('nan')):12.1f} "
              f"{'yes' if info.get('symmetry') else 'no'}")


if __name__ == "__main__":
    main()
