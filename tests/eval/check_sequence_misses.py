"""Checks the miss columns of a `vtloc eval --sequence` report (docs/eval.md): every
window either lands within 5 mm or misses for one of two reasons (search,
ambiguity), so per row and per object the three shares sum to one, each in [0, 1].

    check_sequence_misses.py REPORT.json
"""
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


def main(path):
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
    print(f"ok: {len(j['rows'])} rows, {n} object entries")


if __name__ == "__main__":
    main(*sys.argv[1:])
