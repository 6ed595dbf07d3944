"""Checks what `vtloc eval` wrote: the vtloc-eval/1 JSON (docs/eval.md), the
markdown table, the per-touch CSV (the same touches and numbers as the JSON)
and the --render pictures (k worst + k best, PNG).

    check_outputs.py REPORT.json TABLE.md PER_TOUCH.csv RENDER_DIR K
"""
import csv
import json
import math
import os
import sys


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def main(report, table, per_touch, render_dir, k):
    with open(report) as f:
        j = json.load(f)
    if j.get("format") != "vtloc-eval/1":
        fail(f"format {j.get('format')!r}")
    for key in ("model", "config", "data", "split", "objects", "iters", "topk", "sequence", "rows", "per_touch",
                "time_per_touch_ms"):
        if key not in j:
            fail(f"missing key {key!r}")
    methods = {}
    for r in j["rows"]:
        methods.setdefault(r["method"], []).append(r["subset"])
        for m in ("mm", "nd", "top1", "top5", "mpe"):
            v = r[m]
            if r["objects"] and not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                fail(f"row {r['method']}/{r['subset']}: {m} = {v!r}")
        if r["objects"] and not (0 <= r["top1"] <= r["top5"] <= 100):
            fail(f"row {r['method']}/{r['subset']}: top1 {r['top1']} top5 {r['top5']}")
    for m in (j["config"], "Chance", "Point Filtering", "Codebook"):
        if methods.get(m) != ["non-uniform", "uniform", "all"]:
            fail(f"rows of {m!r}: {methods.get(m)}")
    chance = [r for r in j["rows"] if r["method"] == "Chance"]
    if any(r.get("note") != "analytic" for r in chance):
        fail("the Chance rows do not say 'analytic'")
    all_row = next(r for r in j["rows"] if r["method"] == j["config"] and r["subset"] == "all")
    if all_row["touches"] != len(j["per_touch"]):
        fail(f"'all' row has {all_row['touches']} touches, per_touch {len(j['per_touch'])}")
    if not j["time_per_touch_ms"] > 0:
        fail("time_per_touch_ms is not positive")

    with open(per_touch, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or list(rows[0]) != ["object", "touch", "subset", "error_mm", "nd", "rank", "mpe"]:
        fail(f"CSV header {list(rows[0]) if rows else None}")
    if len(rows) != len(j["per_touch"]):
        fail(f"CSV has {len(rows)} rows, JSON {len(j['per_touch'])}")
    for c, t in zip(rows, j["per_touch"]):
        if (c["object"], int(c["touch"]), int(c["rank"])) != (t["object"], t["touch"], t["rank"]) or \
                abs(float(c["error_mm"]) - t["error_mm"]) > 1e-6 * max(1.0, t["error_mm"]):
            fail(f"CSV row {c} does not match JSON {t}")

    with open(table) as f:
        md = f.read()
    if not md.startswith("| Method | Subset | Objects | Touches | mm Error | ND (%) | Top-1 (%) | Top-5 (%) | MPE |"):
        fail("markdown header")
    if md.count("\n| ") != 1 + 1 + len(j["rows"]) - 1 or "| Chance (analytic) | all |" not in md:
        fail(f"markdown rows:\n{md}")

    pngs = sorted(os.listdir(render_dir))
    worst = [p for p in pngs if p.startswith("worst_")]
    best = [p for p in pngs if p.startswith("best_")]
    if len(worst) != int(k) or len(best) != int(k) or len(pngs) != 2 * int(k):
        fail(f"renders: {pngs}")
    for p in pngs:
        with open(os.path.join(render_dir, p), "rb") as f:
            if f.read(8) != b"\x89PNG\r\n\x1a\n":
                fail(f"{p} is not a PNG")
    print(f"ok: {len(j['rows'])} rows, {len(rows)} touches, renders {pngs}")


if __name__ == "__main__":
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    main(*sys.argv[1:])
