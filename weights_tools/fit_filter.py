"""Fits the multi-touch filter's knobs (SPEC 6) on windows that end at train touches.

Runs `vtloc eval --objects known --sequence 4,8 --geometry-only --end-split train` (windows
ending at the seen objects' train touches; --objects all on a dataset of training objects only) over a small grid of knobs on a dataset and prints, per setting, ND (raw and up to symmetry) at T = 4 and 8
and the belief's calibration; the best by mean ND up to symmetry is the default in
engine/api/vtloc/vtloc.h (TrackerOptions). Test touches are never used.

With --refine, the knob is how much wider the refinement's first climb is than the grid's
widths (refine_widen; 0: straight to the tight widths), at the geometry knobs fitted before.

With --rescue, the knobs are when (rescue_fit) and how many more modes (rescue_modes) the
refinement also climbs when its best mode fits the window poorly (the result and why the
default stays off: docs/multitouch.md, "Refining more modes").

With --reach, the knob is the lever arm (mm) from which the refinement also climbs outward
(refine_reach; 0: the direct climb alone): the window's touches within it first, then twice
it, ..., the better fit kept (docs/multitouch.md, "Climbing from the nearest touches").

With --free-space, the knob is how far behind the gel plane the sensor's pad must be clear of
the object (free_space, mm; 0: off), scored on each refined mode (docs/multitouch.md, "Free space").
With --register, the knob is how many Gauss-Newton rounds register the first modes onto the
surface where nothing refined fits (register; 0: off), scored on the seen objects and, with
--objects all, on a dataset of the smooth objects' windows (docs/multitouch.md, "Registration").
With --deep, the knobs are when the search counts as lost (deep_fit: the best refined fit
after the registration below it) and how many modes the deep search then refines (deep_modes;
0: off), every unrefined mode registered from its best spin (docs/multitouch.md, "Deep search").
With --render, the knobs are render-and-compare's inverse temperature (render_weight, SPEC 9)
and the comparison's cell (render_cell_mm; whether its error also drops a quadratic bowl,
render_quadratic, was fitted before on the same windows, and the press percentile
render_press_percentile on train touches: docs/render_compare.md):
the "MidasTouch-style" row alone (--rows render --render-compare), each frame's gel shape
read from the frame as a robot would. With --oracle, the same knob for the oracle row (the
renderer's true indentation maps: what a perfect gel-shape reader would allow), reported
beside the shipped weight, never shipped.

    python3 -m weights_tools.fit_filter --vtloc build/vtloc --data DIR
        [--refine | --reach | --free-space | --rescue | --register | --render | --oracle]
        [--sequence 4,8] [--out fit.json]
"""
import argparse
import itertools
import json
import os
import subprocess
import tempfile

GRID = {
    "allowance": [0.25, 0.5],
    "sigma_d": [0.5, 0.7, 1.0],
    "sigma_a": [6, 9],
}


GRID_REFINE = {"refine_widen": [0, 2, 4, 8, 16]}
GRID_REACH = {"refine_reach": [0, 10, 15, 20, 30, 45, 60]}
GRID_FREE = {"free_space": [0, 0.5, 1, 1.5, 2, 3, 4, 6]}
# Refining more modes where the best refined one fits the window poorly (rescue_fit: the
# threshold, log; -1e9: never; 0: always, since a fit is at most 0).
GRID_RESCUE = {"rescue_fit": [0, -1, -1e9], "rescue_modes": [24]}
# render_quadratic (1) was fitted before on the same windows: {1, 0} x render_weight {4, 16, 0.25}.
GRID_REGISTER = {"register": [0, 8, 12, 20]}
GRID_DEEP = {"deep_modes": [0, 8, 16], "deep_fit": [-20, -10, -5]}
GRID_RENDER = {"render_cell_mm": [3, 2, 1], "render_weight": [0.25, 1]}
GRID_ORACLE = {"render_weight": [16, 64, 256]}


def run(vtloc, data, objects, knobs, row=None, sequence="4,8"):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "fit.json")
        arg = ",".join(f"{k}={v}" for k, v in knobs.items())
        extra = ["--render-compare", "--rows", row] if row else []
        subprocess.run([vtloc, "eval", "--data", data, "--objects", objects, "--sequence", sequence, "--geometry-only",
                        "--end-split", "train", "--filter", arg, "--json", out] + extra, check=True, stdout=subprocess.DEVNULL)
        with open(out) as f:
            rows = [r for r in json.load(f)["rows"] if r["subset"] == "all" and not r["odometry_noise"]]
    return {f"T{r['T']}": {k: r[k] for k in ("nd", "nd_symmetry", "within_5mm", "mass_within_5mm")} for r in rows}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vtloc", default="build/vtloc")
    ap.add_argument("--data", required=True)
    ap.add_argument("--objects", default="known", help="known (the seen objects) or all")
    ap.add_argument("--refine", action="store_true", help="fit refine_widen (the refinement's first, wider climb)")
    ap.add_argument("--reach", action="store_true", help="fit refine_reach (the refinement's climb from the nearest touches)")
    ap.add_argument("--free-space", action="store_true", help="fit free_space (the pad's clearance behind the gel)")
    ap.add_argument("--rescue", action="store_true", help="fit rescue_fit and rescue_modes (more modes refined where none fits)")
    ap.add_argument("--register", action="store_true", help="fit register (rounds of the registration where none fits)")
    ap.add_argument("--deep", action="store_true", help="fit deep_fit and deep_modes (the deep search where the registered modes fit poorly)")
    ap.add_argument("--render", action="store_true", help="fit render_weight on the render-and-compare row")
    ap.add_argument("--oracle", action="store_true", help="fit render_weight on the oracle-maps row (not shipped)")
    ap.add_argument("--sequence", default="4,8", help="window lengths T scored (default 4,8)")
    ap.add_argument("--out")
    a = ap.parse_args()
    grid = GRID_ORACLE if a.oracle else GRID_RENDER if a.render else GRID_REFINE if a.refine else GRID_REACH if a.reach else GRID_FREE if a.free_space else GRID_RESCUE if a.rescue else GRID_REGISTER if a.register else GRID_DEEP if a.deep else GRID
    row = "oracle" if a.oracle else "render" if a.render else None
    results = []
    for values in itertools.product(*grid.values()):
        knobs = dict(zip(grid, values))
        if a.rescue and knobs["rescue_fit"] < -1e8 and knobs["rescue_modes"] != grid["rescue_modes"][0]:
            continue  # never rescued: one run is enough
        if a.deep and knobs["deep_modes"] == 0 and knobs["deep_fit"] != grid["deep_fit"][0]:
            continue  # off: one run is enough
        r = run(a.vtloc, a.data, a.objects, knobs, row, a.sequence)
        score = sum(v["nd_symmetry"] for v in r.values()) / len(r)
        results.append({"knobs": knobs, "score": score, "rows": r})
        print(json.dumps(knobs), f"mean ND up to symmetry {score:.2f}",
              " ".join(f"{t}: {v['nd']:.1f}/{v['nd_symmetry']:.1f}" for t, v in r.items()), flush=True)
    best = min(results, key=lambda x: x["score"])
    print("best", json.dumps(best["knobs"]), f"{best['score']:.2f}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"grid": grid, "results": results, "best": best}, f, indent=1)


if __name__ == "__main__":
    main()
