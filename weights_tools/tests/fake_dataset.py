"""A tiny dataset in the vtloc-synth/1 layout (docs/dataset.md), for tests.

Clouds are synthetic superellipsoids, frames synthetic tactile images (smooth
random blobs); contacts are cloud points.  Nothing here is physically rendered:
it only has to follow the layout exactly."""

import csv
import json
import os

import numpy as np
from PIL import Image

from weights_tools import synthetic
from weights_tools.dataset import POINT_COLUMNS, TOUCH_COLUMNS


def _frame(normal):
    """Orthonormal sensor frame whose z axis points into the surface (-normal)."""
    z = -normal / np.linalg.norm(normal)
    a = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)  # columns x, y, z


def make_dataset(root, n_objects=3, n_points=128, n_train=6, n_test=4, n_extra=2, seed=0):
    rng = np.random.default_rng(seed)
    os.makedirs(os.path.join(root, "objects"), exist_ok=True)
    entries = []
    for k in range(n_objects):
        name = f"shape{k:02d}"
        subset = "uniform" if k % 2 == 0 else "non-uniform"
        entries.append({"name": name, "subset": subset, "dn_share": 0.9 if k % 2 == 0 else 0.5,
                        "object_split": "seen" if k < max(1, n_objects - 1) else "unseen"})
        folder = os.path.join(root, "objects", name)
        os.makedirs(os.path.join(folder, "touches"), exist_ok=True)
        pts = synthetic.superellipsoid_cloud(100 + k, n_points).astype(np.float64)
        with open(os.path.join(folder, "points.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(POINT_COLUMNS)
            w.writerows([[repr(float(v)) for v in row] for row in pts])
        diam = max(np.linalg.norm(pts[:, None, :3] - pts[None, :, :3], axis=-1).max(), 1e-9)
        ext = pts[:, :3].max(0) - pts[:, :3].min(0)
        with open(os.path.join(folder, "object.json"), "w") as f:
            json.dump({"name": name, "source": f"{name}.off", "scale_mm": float(ext.max()),
                       "diameter_mm": float(diam), "subset": subset,
                       "dn_share": entries[-1]["dn_share"], "n_points": n_points,
                       "sample_seed": 100 + k}, f)
        n = n_train + n_test + n_extra
        idx = rng.choice(n_points, size=n, replace=False)
        splits = ["train"] * n_train + ["test"] * n_test + ["extra"] * n_extra
        rng.shuffle(splits[:n_train + n_test])
        path = rng.permutation(n_train + n_test)  # collection order of the non-extra touches
        order = [-1] * n
        for o, i in enumerate(path):
            order[[j for j, s in enumerate(splits) if s != "extra"][i]] = o
        rows, centres = [], {}
        for i in range(n):
            c, nrm = pts[idx[i], :3], pts[idx[i], 3:]
            R = _frame(nrm)
            t = c + 0.4 * nrm
            centres[i] = t
            img = f"touches/{i:04d}.png"
            Image.fromarray(synthetic.tactile_image(1000 * k + i)).save(os.path.join(folder, img))
            rows.append({"id": i, "split": splits[i], "order": order[i], "image": img, "c": c,
                         "n": nrm, "R": R, "t": t})
        by_order = {r["order"]: r for r in rows if r["order"] >= 0}
        with open(os.path.join(folder, "touches.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(TOUCH_COLUMNS)
            for r in rows:
                prev = by_order.get(r["order"] - 1) if r["order"] > 0 else None
                d = r["t"] - prev["t"] if prev is not None else np.zeros(3)
                q = prev["R"].T @ r["R"] if prev is not None else np.eye(3)
                qt = prev["R"].T @ (r["t"] - prev["t"]) if prev is not None else np.zeros(3)
                vals = ([r["id"], r["split"], r["order"], r["image"]] + list(r["c"]) + list(r["n"])
                        + list(r["R"].reshape(-1)) + list(r["t"]) + [0.5, 10.0, 3.0] + list(d)
                        + list(q.reshape(-1)) + list(qt))
                w.writerow([v if isinstance(v, str) else repr(v if isinstance(v, int) else float(v))
                            for v in vals])
    with open(os.path.join(root, "dataset.json"), "w") as f:
        json.dump({"format": "vtloc-synth/1", "seed": seed,
                   "sensor": {"height": 120, "width": 160, "mm_per_px": 0.1245,
                              "calibration": "objectfolder_gelsight_calib"},
                   "n_points": n_points, "objects": entries}, f, indent=1)
    return root
