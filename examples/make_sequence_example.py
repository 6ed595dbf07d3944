"""Copies one window of a `vtloc synth` dataset's collection tour into examples/ as the
demo's multi-touch sequence: the object's mesh (PLY), the window's frames and a touches
file (vtloc-touches/2, relative motions) that also records each touch's true contact.

    /usr/bin/python3 examples/make_sequence_example.py DATASET OBJECT T NAME

The window is the tour's first one of T touches that ends at a test touch (SPEC 6's rule,
order >= T - 1): fixed by the rule, not picked by how well it localises. The object must be
a procedural shape (CGAL meshes are not committed: their licence)."""

import json
import os
import shutil
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from weights_tools.dataset import read_dataset  # noqa: E402


def rounded(a, nd=6):
    return [rounded(x, nd) for x in a] if isinstance(a, (list, np.ndarray)) else round(float(a), nd)


def main(root, obj_name, T, name):
    ds = read_dataset(root)
    obj = next((o for o in ds.objects if o.name == obj_name), None)
    if obj is None:
        sys.exit(f"{root}: no object '{obj_name}'")
    src = json.load(open(os.path.join(obj.folder, "object.json")))
    if not src.get("source", "").startswith("shape:"):
        sys.exit(f"{obj_name}: not a procedural shape ({src.get('source')}); CGAL meshes are not committed")
    tour = sorted((t for t in obj.touches if t.order >= 0), key=lambda t: t.order)
    end = next(i for i, t in enumerate(tour) if t.split == "test" and t.order >= T - 1)
    window = tour[end - T + 1:end + 1]
    shutil.copyfile(os.path.join(obj.folder, "mesh.ply"), os.path.join(HERE, f"{name}.ply"))
    touches = []
    for k, t in enumerate(window):
        png = f"{name}_{k + 1}.png"
        shutil.copyfile(os.path.join(obj.folder, t.image), os.path.join(HERE, png))
        entry = {"tactile": png}
        if k > 0:
            entry["motion"] = {"Q": rounded(t.rel_R, 9), "q": rounded(t.rel_t)}
        entry["contact"] = rounded(t.contact)  # the truth: the demo prints the error against it
        touches.append(entry)
    info = {
        "format": "vtloc-touches/2",
        "motion": "relative",
        "object": f"{name}.ply",
        "object_diameter_mm": round(float(src["diameter_mm"]), 4),
        "where": f"touches {window[0].order}..{window[-1].order} of the collection tour of '{obj_name}' "
                 f"(vtloc synth --shape {obj_name}, seed {ds.seed}); the last one is test touch {window[-1].id}",
        "units": "mm",
        "frames": "simulated by vtloc synth on the ObjectFolder 2.0 GelSight calibration (CC BY 4.0)",
        "touches": touches,
    }
    with open(os.path.join(HERE, f"{name}.json"), "w") as f:
        json.dump(info, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4])
