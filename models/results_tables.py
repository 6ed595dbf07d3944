"""Markdown tables for docs/results.md from the reports models/results.sh wrote.

    python3 models/results_tables.py OUT_DIR NAME=LABEL [NAME=LABEL ...]

The first NAME is the model of the ILU N ablation. Baseline rows (Chance, Point
Filtering, Codebook) come from the first model's engine report; every model row is this
engine's, with the PyTorch reference's ND beside it.
"""
import json
import os
import re
import sys

# The single-touch baselines of `vtloc eval` (its JSON names), and their tables' labels.
BASELINES = {"Chance": "Chance (analytic)", "Point Filtering": "Point Filtering (single touch)",
             "Codebook": "Codebook (MidasTouch-style)"}


def load(path):
    with open(path) as f:
        return json.load(f)


def row(r):
    return f"{r['mm']:.2f} | {r['nd']:.2f} | {r['top1']:.1f} | {r['top5']:.1f} | {r['mpe']:.3f}"


def main():
    out, pairs = sys.argv[1], [a.split("=", 1) for a in sys.argv[2:]]
    for objects, title in (("known", "Known objects (test contacts of the seen objects)"),
                           ("unknown", "Unknown objects (test contacts of objects never trained on)")):
        print(f"### {title}\n")
        print("| method | subset | objects | touches | mm error | ND (%) | Top-1 (%) | Top-5 (%) | MPE | ND, PyTorch |")
        print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        first = load(os.path.join(out, f"{pairs[0][0]}.{objects}.json"))
        for r in first["rows"]:
            if r["method"] in BASELINES:
                label = BASELINES[r["method"]]
                print(f"| {label} | {r['subset']} | {r['objects']} | {r['touches']} | {row(r)} | - |")
        worst = 0.0
        for name, label in pairs:
            eng = load(os.path.join(out, f"{name}.{objects}.json"))
            ref = {(r["subset"]): r for r in load(os.path.join(out, f"{name}.{objects}.py.json"))["rows"]
                   if r["method"] not in BASELINES}
            for r in eng["rows"]:
                if r["method"] in BASELINES:
                    continue
                p = ref[r["subset"]]
                worst = max(worst, *(abs(r[k] - p[k]) for k in ("mm", "nd", "top1", "top5", "mpe")))
                print(f"| {label} | {r['subset']} | {r['objects']} | {r['touches']} | {row(r)} | {p['nd']:.2f} |")
        print(f"\nLargest difference between this engine and the PyTorch reference over these rows' "
              f"metrics: {worst:.2g}.\n")
    name, label = pairs[0]
    print(f"### ILU iterations N at run time ({label}, known objects)\n")
    print("| N | ND (%) | Top-1 (%) | Top-5 (%) | engine ms per touch (batched) |")
    print("| ---: | ---: | ---: | ---: | ---: |")
    for n in (0, 4, 8, 16, 32):
        j = load(os.path.join(out, f"{name}.iters{n}.json"))
        r = [r for r in j["rows"] if r["subset"] == "all"][0]
        print(f"| {n} | {r['nd']:.2f} | {r['top1']:.1f} | {r['top5']:.1f} | {j['time_per_touch_ms']:.2f} |")


if __name__ == "__main__":
    main()
