"""Compares the model rows of two vtloc-eval/1 reports (docs/eval.md): `vtloc eval`
(this engine) against `python3 -m weights_tools.eval` (the PyTorch reference).

    compare_eval.py ENGINE.json REFERENCE.json DATASET_DIR [--rtol 1e-3]

- The same touches, objects and rows.
- Per touch: error_mm, nd and mpe within rtol (relative; values within 1e-5 of
  each other agree, so an exact 0 matches a float round trip); rank equal, except where
  the two predictions could legitimately order the candidates differently: the
  candidates' distances from the prediction around the rank that differs are closer
  than the predictions' own difference allows (a near tie). Such touches are
  printed, never hidden, and their MPE is exempt (the top-K set may differ).
- Per row: mm, nd, mpe within rtol; the Top-1 / Top-5 counts equal up to the
  near-tie touches.
Prints the largest relative differences; exit status 1 on any disagreement.
"""
import argparse
import csv
import json
import math
import os
import sys


def candidates(dataset, obj):
    """The object's test contacts in id order (docs/dataset.md)."""
    path = os.path.join(dataset, "objects", obj, "touches.csv")
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["split"] == "test"]
    rows.sort(key=lambda r: int(r["id"]))
    return [(float(r["cx"]), float(r["cy"]), float(r["cz"])) for r in rows]


ATOL = 1e-5  # mm, % or MPE: below it two values agree whatever their ratio (e.g. 0 vs 1e-7)


def rel(a, b):
    """Relative difference (reported as it is)."""
    if a is None or b is None:
        return 0.0 if a is None and b is None else math.inf
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def differ(a, b, rtol):
    """Beyond rtol relative, and beyond ATOL absolute."""
    if a is None or b is None:
        return (a is None) != (b is None)
    return abs(a - b) > ATOL and rel(a, b) > rtol


def near_tie(cands, p, q, rank_a, rank_b):
    """True when predictions p and q (object units) may order the candidates
    differently around ranks rank_a..rank_b: the gap between the distances at
    those positions is within twice the predictions' distance (+ 1e-6 slack)."""
    delta = math.dist(p, q)
    d = sorted(math.dist(p, c) for c in cands)
    lo, hi = min(rank_a, rank_b) - 1, max(rank_a, rank_b) - 1
    return d[hi] - d[lo] <= 2 * delta + 1e-6 * max(d[hi], 1.0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("engine")
    ap.add_argument("reference")
    ap.add_argument("dataset")
    ap.add_argument("--rtol", type=float, default=1e-3)
    a = ap.parse_args()
    with open(a.engine) as f:
        E = json.load(f)
    with open(a.reference) as f:
        R = json.load(f)
    problems = []
    for key in ("format", "config", "split", "objects", "topk", "sequence", "mm_per_px"):
        if E.get(key) != R.get(key):
            problems.append(f"'{key}' differs: {E.get(key)!r} vs {R.get(key)!r}")
    topk = E.get("topk", 5)

    et = {(t["object"], t["touch"]): t for t in E["per_touch"]}
    rt = {(t["object"], t["touch"]): t for t in R["per_touch"]}
    if set(et) != set(rt):
        problems.append(f"different touches: engine only {sorted(set(et) - set(rt))}, "
                        f"reference only {sorted(set(rt) - set(et))}")
    worst = {"error_mm": (0.0, None, 0.0), "nd": (0.0, None, 0.0), "mpe": (0.0, None, 0.0)}
    ties = set()
    cache = {}
    for key in sorted(set(et) & set(rt)):
        e, r = et[key], rt[key]
        if e["rank"] != r["rank"]:
            cands = cache.setdefault(key[0], candidates(a.dataset, key[0]))
            if near_tie(cands, e["contact"], r["contact"], e["rank"], r["rank"]):
                ties.add(key)
                print(f"near tie (not counted): {key[0]} touch {key[1]}: rank {e['rank']} vs {r['rank']}")
            else:
                problems.append(f"{key[0]} touch {key[1]}: rank {e['rank']} vs {r['rank']}")
        for m in worst:
            if m == "mpe" and key in ties:
                continue
            d = rel(e[m], r[m])
            if d > worst[m][0]:
                worst[m] = (d, key, abs(e[m] - r[m]))
            if differ(e[m], r[m], a.rtol):
                problems.append(f"{key[0]} touch {key[1]}: {m} {e[m]!r} vs {r[m]!r} (relative {d:.2e})")

    model = E["config"]
    erows = {r["subset"]: r for r in E["rows"] if r["method"] == model}
    rrows = {r["subset"]: r for r in R["rows"] if r["method"] == model}
    if set(erows) != set(rrows) or not erows:
        problems.append(f"model rows differ: {sorted(erows)} vs {sorted(rrows)}")
    row_worst = 0.0
    for subset in sorted(set(erows) & set(rrows)):
        e, r = erows[subset], rrows[subset]
        for k in ("objects", "touches"):
            if e[k] != r[k]:
                problems.append(f"row {subset}: {k} {e[k]} vs {r[k]}")
        in_row = [k for k in ties if subset == "all" or et[k]["subset"] == subset]
        for m in ("mm", "nd", "mpe"):
            d = rel(e[m], r[m])
            row_worst = max(row_worst, d)
            if differ(e[m], r[m], a.rtol) and not (m == "mpe" and in_row):
                problems.append(f"row {subset}: {m} {e[m]!r} vs {r[m]!r} (relative {d:.2e})")
        for m in ("top1", "top5"):
            if (e[m] is None) != (r[m] is None) or (e[m] is not None and abs(e[m] - r[m]) > 1e-9 and not in_row):
                problems.append(f"row {subset}: {m} {e[m]!r} vs {r[m]!r}")

    n_top1 = sum(1 for t in et.values() if t["rank"] == 1)
    n_top5 = sum(1 for t in et.values() if t["rank"] <= 5)
    print(f"{len(et)} touches, {len(erows)} model rows (top-{topk}); engine Top-1 {n_top1}, Top-5 {n_top5}; "
          f"{len(ties)} near ties")
    for m, (d, key, diff) in worst.items():
        print(f"largest relative difference per touch, {m}: {d:.3e}" +
              (f" ({key[0]} touch {key[1]}, absolute {diff:.3e})" if key else ""))
    print(f"largest relative difference over the rows' mm/nd/mpe: {row_worst:.3e}")
    for p in problems:
        print("MISMATCH:", p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
