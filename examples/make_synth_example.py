"""Copies one test touch of a `vtloc synth` dataset into examples/ as a demo example:
the object's cloud (PLY with normals, exactly the dataset's points), its candidates
(the object's test contacts), the touch's frame and a JSON with the ground truth.

    /usr/bin/python3 examples/make_synth_example.py DATASET OBJECT TOUCH_ID NAME

The object must not be a CGAL mesh (their licence keeps them out of the repository):
use a procedural shape (shape:...)."""

import json
import os
import shutil
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from weights_tools.dataset import read_dataset  # noqa: E402
from weights_tools.ply import write_ply  # noqa: E402


def main(root, obj_name, touch_id, name):
    ds = read_dataset(root)
    obj = next((o for o in ds.objects if o.name == obj_name), None)
    if obj is None:
        sys.exit(f"{root}: no object '{obj_name}'")
    src = json.load(open(os.path.join(obj.folder, "object.json")))
    if not src.get("source", "").startswith("shape:"):
        sys.exit(f"{obj_name}: not a procedural shape ({src.get('source')}); CGAL meshes are not committed")
    touch = next((t for t in obj.touches if t.id == touch_id), None)
    if touch is None or touch.split != "test":
        sys.exit(f"{obj_name}: touch {touch_id} is not a test touch")
    write_ply(os.path.join(HERE, f"{name}.ply"), np.asarray(obj.points, dtype=np.float32))
    with open(os.path.join(HERE, f"{name}_candidates.csv"), "w") as f:
        f.write(f"# the {len(obj.candidates)} test contacts of '{obj_name}' (mm), its candidate set\n# x,y,z\n")
        for c in obj.candidates:
            f.write(f"{c[0]:.6f},{c[1]:.6f},{c[2]:.6f}\n")
    png = f"{name}_touch.png"
    shutil.copyfile(os.path.join(obj.folder, touch.image), os.path.join(HERE, png))
    info = {
        "object": f"{name}.ply", "tactile": png, "candidates": f"{name}_candidates.csv",
        "contact": [round(float(v), 6) for v in touch.contact],
        "contact_normal": [round(float(v), 6) for v in touch.normal],
        "where": f"test touch {touch_id} of '{obj_name}' ({obj.subset}, {obj.object_split} object)",
        "units": "mm",
        "frame": f"simulated by vtloc synth (dataset seed {ds.seed}) on the ObjectFolder 2.0 GelSight "
                 "calibration (CC BY 4.0)",
        "press_mm": round(float(touch.press_mm), 4), "spin_deg": round(float(touch.spin_deg), 3),
        "object_diameter_mm": round(float(src["diameter_mm"]), 4),
    }
    with open(os.path.join(HERE, f"{name}.json"), "w") as f:
        json.dump(info, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4])
