"""Fixture for the provenance warning of `vtloc eval`: a copy of a dataset in
which one object is marked unseen (never trained on), and a copy of a weight
file whose metadata says it was trained on that object.

    make_provenance.py DATASET OBJECT WEIGHTS OUT_DIR
writes OUT_DIR/ds_unseen/ and OUT_DIR/provenance.safetensors.
"""
import json
import os
import shutil
import struct
import sys


def main(dataset, obj, weights, out):
    ds = os.path.join(out, "ds_unseen")
    shutil.rmtree(ds, ignore_errors=True)
    shutil.copytree(dataset, ds)
    index = os.path.join(ds, "dataset.json")
    with open(index) as f:
        d = json.load(f)
    names = [o["name"] for o in d["objects"]]
    if obj not in names:
        sys.exit(f"{index}: no object {obj!r} (has {names})")
    for o in d["objects"]:
        o["object_split"] = "unseen" if o["name"] == obj else "seen"
    with open(index, "w") as f:
        json.dump(d, f, indent=1)

    with open(weights, "rb") as f:
        raw = f.read()
    n = struct.unpack("<Q", raw[:8])[0]
    header = json.loads(raw[8:8 + n])
    meta = header.setdefault("__metadata__", {})
    meta["vtloc.provenance"] = json.dumps(
        {"dataset": "test", "objects": [{"name": name, "object_split": "seen"} for name in names]})
    text = json.dumps(header, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 8)  # keep the data area 8-byte aligned
    with open(os.path.join(out, "provenance.safetensors"), "wb") as f:
        f.write(struct.pack("<Q", len(text)) + text + raw[8 + n:])


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
