"""Markdown tables for docs/results.md from the reports models/results.sh wrote.

    python3 models/results_tables.py OUT_DIR NAME=LABEL [NAME=LABEL ...]

The first NAME is the model of the ILU N ablation. Baseline rows (Chance, Point
Filtering, Codebook) come from the first model's engine report; every model row is this
engine's, with the PyTorch reference's ND beside it. The several-touch tables (SPEC 6)
come from sequence.{known,unknown}.json: ND against T per method, and per object the
geometry rows at T = 8 with why each window missed (search or ambiguity).
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
    sequence_tables(out)


SEQ_METHODS = ["Geometry", "Geometry + network", "Geometry + network (test frames)",
               "Geometry + render-and-compare (MidasTouch-style)", "Geometry + render-and-compare (oracle maps)"]


def sequence_tables(out):
    for objects, title in (("known", "Known objects (seen; windows ending at their test touches)"),
                           ("unknown", "Unknown objects (unseen)")):
        path = os.path.join(out, f"sequence.{objects}.json")
        if not os.path.exists(path):
            continue
        j = load(path)
        rows = {(r["method"], r["odometry_noise"], r["T"], r["subset"]): r for r in j["rows"]}
        Ts = sorted({r["T"] for r in j["rows"]})
        print(f"### Several touches: {title}, ND % (up to symmetry)\n")
        print("| method | odometry noise | " + " | ".join(f"T = {t}" for t in Ts) +
              " | T = 8, candidates | T = 4, candidates: non-uniform / uniform |")
        print("| --- | --- |" + " --- |" * (len(Ts) + 2))
        for m in SEQ_METHODS:
            for noise in (False, True):
                if (m, noise, Ts[0], "all") not in rows:
                    continue
                cells = [f"{rows[m, noise, t, 'all']['nd']:.1f} ({rows[m, noise, t, 'all']['nd_symmetry']:.1f})" for t in Ts]
                c8 = rows.get((m, noise, 8, "all"))
                c4 = [rows.get((m, noise, 4, s)) for s in ("non-uniform", "uniform")]
                cells.append(f"{c8['nd_candidates']:.1f}" if c8 else "-")
                cells.append(" / ".join(f"{r['nd_candidates']:.1f}" if r else "-" for r in c4))
                print(f"| {m} | {'0.5 mm, 0.5 deg' if noise else 'no'} | " + " | ".join(cells) + " |")
        per = j["per_object"].get("Geometry T8")
        if not per:
            continue
        print(f"\n#### Per object, geometry alone, T = 8 ({objects}): why the misses\n")
        print("Windows more than 5 mm off: *search* when the true pose, refined, fits the window's geometry "
              "better than the estimate's (the grid or the refinement missed it), else *ambiguity* (a wrong pose "
              "fits as well). Shares of the object's windows.\n")
        print("| object | windows | ND % | up to symmetry | within 5 mm | missed: search | missed: ambiguity |")
        print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
        for name, o in sorted(per.items(), key=lambda kv: kv[1]["nd"]):
            s, a = o.get("missed_search"), o.get("missed_ambiguity")
            if s is None:
                print(f"| {name} | {o['touches']} | {o['nd']:.1f} | {o['nd_symmetry']:.1f} | - | - | - |")
            else:
                print(f"| {name} | {o['touches']} | {o['nd']:.1f} | {o['nd_symmetry']:.1f} | {max(0.0, 1 - s - a):.2f} | {s:.2f} | {a:.2f} |")
        print()


if __name__ == "__main__":
    main()
