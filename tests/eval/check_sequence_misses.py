"""Checks the miss columns of a `vtloc eval --sequence` report (docs/eval.md): every
window either lands within 5 mm or misses for one of two reasons (search,
ambiguity), so per row and per object the three shares sum to one, each in [0, 1].

    check_sequence_misses.py REPORT.json [WINDOWS.csv]

With the report's --per-touch file, also: each object's windows average to its
per-object ND, ND up to symmetry and miss shares (search, ambiguity), row by
row, and a line is marked missed exactly when it is more than 5 mm off.
"""
import csv
import json
import sys


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def check(where, within, search, ambiguity):
    for name, v in (("within_5mm", within), ("missed_search", search), ("missed_ambiguity", ambiguity)):
        if not 0 <= v <= 1:
            fail(f"{where}: {name} = {v} is not a share")
    if abs(within + search + ambiguity - 1) > 1e-9:
        fail(f"{where}: within 5 mm {within} + missed (search) {search} + missed (ambiguity) {ambiguity} != 1")


def check_windows(j, path):
    groups = {}
    with open(path) as f:
        for w in csv.DictReader(f):
            row = w["method"] + (" (noise)" if w["odometry_noise"] == "yes" else "") + " T" + w["T"]
            if w["missed"] not in ("", "search", "ambiguity"):
                fail(f"{path}: missed is {w['missed']!r}")
            mm = float(w["error_mm"])  # 4 decimals: within 1e-3 of 5 mm either is right
            if abs(mm - 5) > 1e-3 and (w["missed"] == "") != (mm < 5):
                fail(f"{path}: {w['object']} touch {w['touch']} {row}: {w['error_mm']} mm off, missed {w['missed']!r}")
            groups.setdefault((row, w["object"]), []).append(w)
    for row, objs in j["per_object"].items():
        for name, o in objs.items():
            ws = groups.pop((row, name), [])
            if len(ws) != o["touches"]:
                fail(f"{row} {name}: {len(ws)} window lines for {o['touches']} windows")
            for key, col in (("nd", "nd"), ("nd_symmetry", "nd_symmetry")):
                mean = sum(float(w[col]) for w in ws) / len(ws)
                if abs(mean - o[key]) > 1e-3 + 1e-4 * abs(o[key]):  # the file keeps 4 decimals
                    fail(f"{row} {name}: windows' mean {col} {mean} against the report's {o[key]}")
            for kind in ("search", "ambiguity"):
                share = sum(w["missed"] == kind for w in ws) / len(ws)
                if abs(share - o["missed_" + kind]) > 1e-9:
                    fail(f"{row} {name}: windows' {kind} share {share} against {o['missed_' + kind]}")
    if groups:
        fail(f"window lines of rows or objects the report lacks: {sorted(groups)[:3]}")


def main(path, windows=None):
    with open(path) as f:
        j = json.load(f)
    if j.get("format") != "vtloc-eval-sequence/1":
        fail(f"format {j.get('format')!r}")
    for r in j["rows"]:
        check(f"{r['method']} T={r['T']} {r['subset']}", r["within_5mm"], r["missed_search"], r["missed_ambiguity"])
    n = 0
    for row, objs in j["per_object"].items():
        for name, o in objs.items():
            if not {"missed_search", "missed_ambiguity"} <= o.keys():
                fail(f"{row} {name}: no miss shares")
            n += 1
    if not j["rows"] or not n:
        fail("no rows")
    if windows:
        check_windows(j, windows)
    print(f"ok: {len(j['rows'])} rows, {n} object entries" + (", window lines agree" if windows else ""))


if __name__ == "__main__":
    main(*sys.argv[1:])
