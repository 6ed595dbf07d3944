"""How much of a symmetric object's ND up to symmetry no geometry-only method can remove.

    /usr/bin/python3 models/slide_floor.py --data DIR --per-touch SEQ.csv [OBJECT ...]

SEQ.csv: `vtloc eval --sequence 8 --geometry-only --per-touch` on DIR. For each window of
each object that declares a symmetry axis, the window's true pose is slid along the axis
(1 mm steps, +-100 mm) and refined (Tracker.window_fit); slides that fit the window's geometry
within 1 nat of the truth are poses the touches cannot tell apart (slides within REACH_MM, which
the refinement climbs back from, do not count). Under a belief spread evenly
over them the Bayes estimate is their median, which errs by |median slide|: that, over the
object's diameter, is the window's floor. Prints it per window beside the filter's own ND up
to symmetry (docs/results.md, "What the symmetric objects' misses are").
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from weights_tools.dataset import read_dataset  # noqa: E402 (the repository root, put on the path above)

REACH_MM = 8  # the slides window_fit's climb returns from (4-7 mm on the cylinders)


def rigid(R, t):
    P = np.eye(4)
    P[:3, :3], P[:3, 3] = R, t
    return P


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--per-touch", required=True)
    ap.add_argument("--build", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "python"))
    ap.add_argument("objects", nargs="*")
    a = ap.parse_args()
    sys.path.insert(0, a.build)
    import vtloc
    ctx = vtloc.Context()
    windows = [r for r in csv.DictReader(open(a.per_touch))
               if r["T"] == "8" and r["method"] == "Geometry" and r["odometry_noise"] == "no"]
    data = read_dataset(a.data, check_images=False)
    for obj in a.objects or sorted({w["object"] for w in windows}):
        o = data.object(obj)
        meta = json.load(open(os.path.join(o.folder, "object.json")))
        if not meta.get("symmetry"):
            continue
        axis, diam = np.array(meta["symmetry"]["axis"], float), o.diameter_mm
        by_order = {t.order: t for t in o.touches if t.order >= 0}
        tracker = vtloc.Tracker(ctx, os.path.join(o.folder, "mesh.ply"))
        floors, got = [], []
        for w in (w for w in windows if w["object"] == obj):
            end = int(w["order"])
            motions = [rigid(by_order[k].rel_R, by_order[k].rel_t) for k in range(end - 6, end + 1)]
            truth = rigid(by_order[end].R, by_order[end].t)
            fit = tracker.window_fit(motions, truth)
            alike = []
            for s in np.arange(-100, 100.5, 1.0):
                S = np.eye(4)
                S[:3, 3] = s * axis
                if tracker.window_fit(motions, S @ truth) >= fit - 1:
                    alike.append(s)
            # Slides of a few mm are climbed back to the truth by window_fit's own refinement:
            # only a wider set of alike slides is an ambiguity.
            wide = max(abs(min(alike)), abs(max(alike))) > REACH_MM
            floors.append(abs(float(np.median(alike))) / diam * 100 if wide else 0.0)
            got.append(float(w["nd_symmetry"]))
            print(f"{obj} window ending at order {end}: slides fitting alike {min(alike):+.0f}..{max(alike):+.0f} mm, "
                  f"floor {floors[-1]:.2f} %, the filter {got[-1]:.2f} %", flush=True)
        if floors:
            print(f"{obj}: {len(floors)} windows, floor {np.mean(floors):.2f} %, the filter {np.mean(got):.2f} % (ND up to symmetry)")


if __name__ == "__main__":
    main()
