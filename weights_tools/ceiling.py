"""How much can one touch say about where it was?  A model-free bound for the
synthetic benchmark (docs/results.md, "What one touch carries").

Each test touch of an object is matched against the object's training renders
(``train`` + ``extra``) by its ground-truth indentation map (``vtloc synth
--indentation``) or by its frame minus the empty-sensor frame, searching
rotations about the sensor axis (spins are random), and predicts the geometric
median of the contacts of its k best matches.  ND (SPEC 5) is reported per object
and per subset beside the best constant (the geometric median of all training
contacts) and the nearest training contact to the truth (how dense the renders are).

  python3 -m weights_tools.ceiling --data DIR [--k 1,5,20,80] [--objects a,b] [--json F]
  python3 -m weights_tools.ceiling --data DIR --same-place V   (checks the matcher)
"""

import argparse
import functools
import json
import math
import os
import sys

import numpy as np
import torch
import torch.nn.functional as F
from PIL import Image

from .dataset import DatasetError, read_dataset

POOL = 4        # 120 x 160 maps -> 30 x 40: sensor-scale shape, not pixel noise
ANGLES = 24     # rotation search in 15 degree steps


def geometric_median(points, iters=200):
    """Weiszfeld's iteration: the point with the least summed distance (the best
    constant under ND, which is a distance, not a squared one)."""
    x = points.mean(0)
    for _ in range(iters):
        d = np.maximum(np.linalg.norm(points - x, axis=1), 1e-9)
        x = (points / d[:, None]).sum(0) / (1 / d).sum()
    return x


def disc(h, w):
    """The disc inside an h x w map: what stays in view under any rotation."""
    ys, xs = np.mgrid[0:h, 0:w]
    r = min(h, w) / 2 - 0.5
    return torch.from_numpy((ys - (h - 1) / 2) ** 2 + (xs - (w - 1) / 2) ** 2 <= r * r)


def rotated(x, angles=ANGLES):
    """1 x h x w -> angles x h x w, rotated about the centre in pixel units."""
    h, w = x.shape[-2:]
    th = torch.arange(angles, dtype=torch.float32) * (2 * math.pi / angles)
    c, s = torch.cos(th)[:, None, None], torch.sin(th)[:, None, None]
    ys, xs = torch.meshgrid(torch.linspace(-1, 1, h), torch.linspace(-1, 1, w), indexing="ij")
    X, Y = xs * (w / 2), ys * (h / 2)
    grid = torch.stack([(c * X - s * Y) / (w / 2), (s * X + c * Y) / (h / 2)], -1)
    return F.grid_sample(x[None].expand(angles, -1, -1, -1), grid, align_corners=True)[:, 0]


def descriptors(maps, mask, plane):
    """n x h x w -> n x P: the disc's values, zero-mean, minus their best plane
    (with ``plane``: the sensor's tilt adds one), unit norm, so a dot product is a
    normalised cross-correlation that ignores press depth and contrast."""
    v = maps[:, mask]
    v = v - v.mean(1, keepdim=True)
    if plane:
        ys, xs = torch.nonzero(mask, as_tuple=True)
        A = torch.stack([xs, ys], 1).float()
        A = A - A.mean(0)
        v = v - (A @ torch.linalg.lstsq(A, v.t()).solution).t()
    return v / v.norm(dim=1, keepdim=True).clamp_min(1e-9)


def pooled(maps):
    return F.avg_pool2d(torch.from_numpy(np.stack(maps).astype(np.float32))[:, None], POOL)[:, 0]


def best_similarity(q, db, mask, plane):
    """NCC of one query map (h x w) with every database descriptor, the best over rotations."""
    return (descriptors(rotated(q[None]), mask, plane) @ db.t()).max(0).values


def knn_predictions(db, db_contacts, queries, ks, mask, plane):
    """For each query map (h x w), the geometric median of the contacts of its
    max(ks) best matches over rotations, for every k of ``ks``: n x len(ks) x 3."""
    out = []
    for q in queries:
        order = torch.argsort(best_similarity(q, db, mask, plane), descending=True).numpy()
        out.append([geometric_median(db_contacts[order[:k]]) for k in ks])
    return np.array(out)


def _read(path, what):
    try:
        with Image.open(path) as im:
            return np.asarray(im if what == "depth" else im.convert("RGB"), dtype=np.float32)
    except OSError as e:
        raise DatasetError(f"{path}: cannot read the {what} image ({e})") from None


def object_maps(obj, touches, source):
    """Pooled maps of ``touches``: the true indentation, or the frame minus the
    object's empty-sensor frame averaged over the channels."""
    if source == "depth":
        return pooled([_read(os.path.join(obj.folder, t.image[:-4] + ".depth.png"), "depth") for t in touches])
    background = _background(obj.folder)
    return pooled([(_read(obj.image_path(t), "frame") - background).mean(-1) for t in touches])


@functools.lru_cache(maxsize=4)
def _background(folder):
    # Read once per object: its training renders and its test touches both subtract it.
    return _read(os.path.join(folder, "background.png"), "background")


def database(obj, touches, source):
    """(maps, disc mask, plane removal?, descriptors) of ``touches`` by ``source``."""
    maps = object_maps(obj, touches, source)
    mask, plane = disc(*maps.shape[-2:]), source == "depth"
    return maps, mask, plane, descriptors(maps, mask, plane)


def evaluate_object(obj, ks, sources=("depth", "frame")):
    """{"const", "nearest", "<source>@<k>"...}: ND (%) averaged over the test touches."""
    db_t, tests = obj.touches_of("train", "extra"), obj.touches_of("test")
    if not db_t or not tests:
        raise DatasetError(f"{obj.folder}: needs training and test touches")
    db_c = np.stack([t.contact for t in db_t])
    truth = np.stack([t.contact for t in tests])
    nd = lambda pred: float(100 * np.linalg.norm(pred - truth, axis=-1).mean() / obj.diameter_mm)
    row = {"const": nd(geometric_median(db_c)[None]),
           "nearest": float(100 * np.mean([np.linalg.norm(db_c - c, axis=1).min() for c in truth])
                            / obj.diameter_mm)}
    for src in sources:
        _, mask, plane, db = database(obj, db_t, src)
        preds = knn_predictions(db, db_c, object_maps(obj, tests, src), ks, mask, plane)
        for j, k in enumerate(ks):
            row[f"{src}@{k}"] = nd(preds[:, j])
    return row


def same_place_rate(obj, views, source):
    """With ``vtloc synth --extra-views V``: the share of extra renders whose best
    match among the others (over rotations) is a render of the same contact, i.e.
    how well the matcher sees through spin, press, tilt and look."""
    extra = obj.touches_of("extra")
    maps, mask, plane, db = database(obj, extra, source)
    hits = 0
    for i in range(len(extra)):
        sim = best_similarity(maps[i], db, mask, plane)
        sim[i] = -math.inf
        hits += int(sim.argmax()) // views == i // views
    return hits / len(extra)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--k", default="1,5,20,80")
    ap.add_argument("--objects", default="", help="comma-separated names (default: all)")
    ap.add_argument("--json", default="")
    ap.add_argument("--same-place", type=int, default=0, metavar="V",
                    help="instead: how often the best match of an extra render is one of the V-1 other "
                         "renders of its contact (a dataset built with --extra-views V)")
    args = ap.parse_args(argv)
    ks = [int(k) for k in args.k.split(",")]
    ds = read_dataset(args.data)
    wanted = set(filter(None, args.objects.split(",")))
    if args.same_place:
        for o in ds.objects:
            if not wanted or o.name in wanted:
                print(o.name, " ".join(f"{src} {100 * same_place_rate(o, args.same_place, src):.1f} %"
                                       for src in ("depth", "frame")))
        return 0
    rows = {}
    for o in ds.objects:
        if wanted and o.name not in wanted:
            continue
        r = evaluate_object(o, ks)
        rows[o.name] = {"subset": o.subset, "object_split": o.object_split, "nd": r}
        print(f"{o.name:18s} {o.subset:12s}", " ".join(f"{k} {v:5.1f}" for k, v in r.items()), flush=True)
    summary = {}
    for sub in ("non-uniform", "uniform", "all"):
        sel = [r["nd"] for r in rows.values() if sub in ("all", r["subset"])]
        if sel:
            summary[sub] = {k: float(np.mean([r[k] for r in sel])) for k in sel[0]}
            print(f"{sub:12s} ({len(sel)} objects)", " ".join(f"{k} {v:5.2f}" for k, v in summary[sub].items()))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"data": os.path.abspath(args.data), "k": ks, "pool": POOL, "angles": ANGLES,
                       "objects": rows, "subsets": summary}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
