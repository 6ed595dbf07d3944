"""Metrics of SPEC section 5 as docs/eval.md defines them, in float64.

Per touch: ``touch_metrics`` (error_mm, nd, rank, mpe).  Per report row:
``aggregate`` (mean over an object's touches, then over the row's objects).
"""

import math

import numpy as np
import torch

from . import post

ROWS = ("non-uniform", "uniform", "all")


class ObjectFrame:
    """What the metrics need of one object: cloud, candidates, frame, D."""

    def __init__(self, points, candidates):
        p = torch.as_tensor(np.asarray(points)[:, :3], dtype=torch.float64)
        self.centre, self.scale = post.normalisation(p)
        self.xyz = p                                     # mm
        self.xyz_n = (p - self.centre) / self.scale      # normalised, float64
        self.cand = torch.as_tensor(np.asarray(candidates), dtype=torch.float64).reshape(-1, 3)
        self.cand_n = (self.cand - self.centre) / self.scale
        self.D = diameter(p)

    def normalise(self, x):
        return (torch.as_tensor(np.asarray(x), dtype=torch.float64) - self.centre) / self.scale

    def to_object(self, x_n):
        return torch.as_tensor(x_n, dtype=torch.float64) * self.scale + self.centre


def diameter(xyz, chunk=2048):
    """D: the largest distance between two points (float64, chunked for large N)."""
    p = torch.as_tensor(np.asarray(xyz) if not torch.is_tensor(xyz) else xyz).double()[:, :3]
    best = 0.0
    for i in range(0, p.shape[0], chunk):
        d = ((p[i:i + chunk, None, :] - p[None, :, :]) ** 2).sum(-1)
        best = max(best, float(d.max()))
    return math.sqrt(best)


def _sqd(a, b):
    d = a - b
    return (d * d).sum(-1)


def first_argmin(v):
    """Index of the smallest value, the lowest index on a tie."""
    v = torch.as_tensor(v)
    return int(torch.nonzero(v == v.min())[0, 0])


def rank_order(contact_n, cand_n):
    """Candidate indices by ||c - c_j||^2 ascending, ties to the lower index."""
    s = _sqd(cand_n, torch.as_tensor(contact_n, dtype=torch.float64).reshape(1, 3))
    return torch.sort(s, stable=True).indices


def gt_candidate(gt_n, cand_n):
    """The candidate nearest to c^gt (lowest index on a tie)."""
    return first_argmin(_sqd(cand_n, torch.as_tensor(gt_n, dtype=torch.float64).reshape(1, 3)))


def gt_heatmap(xyz_n, gt_n):
    """G: min-max normalised exp(-||p - c^gt||) over the cloud (zeros when flat)."""
    g = torch.exp(-torch.sqrt(_sqd(xyz_n, torch.as_tensor(gt_n, dtype=torch.float64).reshape(1, 3))))
    lo, hi = g.min(), g.max()
    return torch.zeros_like(g) if hi == lo else (g - lo) / (hi - lo)


def mpe(heat, gt_heat):
    return float((torch.as_tensor(heat).double() - gt_heat).abs().mean())


def touch_metrics(frame, pred_obj, gt_obj, topk=5, heat=None):
    """One touch.  pred_obj, gt_obj: 3 (object units).  ``heat``: the heat-map H to
    score (default: the SPEC 3 heat-map of the top-K candidates around the prediction).
    Returns dict(error_mm, nd, rank, mpe)."""
    pred = torch.as_tensor(np.asarray(pred_obj), dtype=torch.float64).reshape(3)
    gt = torch.as_tensor(np.asarray(gt_obj), dtype=torch.float64).reshape(3)
    err = float(torch.linalg.vector_norm(pred - gt))
    pred_n, gt_n = frame.normalise(pred), frame.normalise(gt)
    order = rank_order(pred_n, frame.cand_n)
    g = gt_candidate(gt_n, frame.cand_n)
    rank = int(torch.nonzero(order == g)[0, 0]) + 1
    if heat is None:
        k = min(int(topk), frame.cand_n.shape[0])
        heat = post.heatmap(frame.xyz_n, frame.cand_n[order[:k]])
    return {"error_mm": err, "nd": 100.0 * err / frame.D, "rank": rank,
            "mpe": mpe(heat, gt_heatmap(frame.xyz_n, gt_n))}



def aggregate(per_touch, subsets, method):
    """Rows non-uniform / uniform / all from per-touch dicts (keys object, error_mm, nd,
    rank, mpe).  ``subsets``: object name -> subset.  Each object is averaged over its
    touches first.  A row without objects has null metrics."""
    by_obj = {}
    for r in per_touch:
        by_obj.setdefault(r["object"], []).append(r)
    per_obj = {}
    for name, rs in by_obj.items():
        per_obj[name] = {
            "mm": np.mean([r["error_mm"] for r in rs]),
            "nd": np.mean([r["nd"] for r in rs]),
            "top1": 100.0 * np.mean([r["rank"] == 1 for r in rs]),
            "top5": 100.0 * np.mean([r["rank"] <= 5 for r in rs]),
            "mpe": np.mean([r["mpe"] for r in rs]),
            "n": len(rs),
        }
    rows = []
    for subset in ROWS:
        names = [n for n in per_obj if subset == "all" or subsets[n] == subset]
        row = {"method": method, "subset": subset, "objects": len(names),
               "touches": int(sum(per_obj[n]["n"] for n in names))}
        for key in ("mm", "nd", "top1", "top5", "mpe"):
            row[key] = float(np.mean([per_obj[n][key] for n in names])) if names else None
        rows.append(row)
    return rows
