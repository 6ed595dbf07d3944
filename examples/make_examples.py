"""Regenerates the example data in this folder (see README.md):

    /usr/bin/python3 examples/make_examples.py [--gelsight PATH]

mug.glb          a mug (body + handle), millimetres, +y up, with vertex normals
touch_0K.png     real GelSight frames (ObjectFolder 2.0, CC BY 4.0) used as example inputs
touch_0K.json    the example's true contact point on the mug (a mesh vertex, so exactly on it)
mug_candidates.csv  twelve candidate contact points on the mug, the three true ones among them

Deterministic: no random numbers; coordinates are rounded to 1e-4 mm before
they are stored, so small libm differences do not change the bytes.
Needs numpy and PIL (Debian's python3-numpy, python3-pil).
"""

import argparse
import json
import math
import struct
from pathlib import Path

import numpy as np
from PIL import Image

HERE = Path(__file__).resolve().parent
DEFAULT_GELSIGHT = HERE.parent.parent / "shared/data/gelsight/objectfolder_gelsight_calib.safetensors"

SEGMENTS = 48           # around the mug's axis
R_OUT, R_IN = 40.0, 36.0  # wall radii, mm
HEIGHT, FLOOR = 95.0, 6.0  # outer height and inner floor height, mm


class Surface:
    """Vertices, normals and outward-facing triangles of one primitive."""

    def __init__(self):
        self.pos, self.nrm, self.tri = [], [], []

    def grid(self, points, normals):
        """points, normals: rows x cols x 3 arrays; a quad strip between neighbouring rows and columns."""
        rows, cols = points.shape[:2]
        base = len(self.pos)
        self.pos += list(points.reshape(-1, 3))
        self.nrm += list(normals.reshape(-1, 3))
        for r in range(rows - 1):
            for c in range(cols - 1):
                a, b = base + r * cols + c, base + r * cols + c + 1
                d, e = a + cols, b + cols
                for t in ((a, b, e), (a, e, d)):
                    self.add_oriented(t)

    def add_oriented(self, t):
        """Counter-clockwise seen from outside: the face normal agrees with the vertex normals."""
        p = [np.asarray(self.pos[i]) for i in t]
        face = np.cross(p[1] - p[0], p[2] - p[0])
        if np.linalg.norm(face) < 1e-12:
            return  # collapsed quad corner at the axis
        if np.dot(face, sum(np.asarray(self.nrm[i]) for i in t)) < 0:
            t = (t[0], t[2], t[1])
        self.tri.append(t)


def revolve(surface, profile, normals):
    """Surface of revolution about +y: profile (radius, y) rows with 2D normals (dr, dy)."""
    ang = np.linspace(0, 2 * math.pi, SEGMENTS + 1)
    ang[-1] = 0.0  # the seam's duplicated column sits exactly on the first
    ca, sa = np.cos(ang), np.sin(ang)
    pr, py = np.asarray(profile, float).T
    nr, ny = np.asarray(normals, float).T
    pts = np.stack([pr[:, None] * ca, np.repeat(py[:, None], len(ang), 1), pr[:, None] * sa], -1)
    nrm = np.stack([nr[:, None] * ca, np.repeat(ny[:, None], len(ang), 1), nr[:, None] * sa], -1)
    surface.grid(pts, nrm)


def mug_body():
    s = Surface()
    lin = np.linspace
    revolve(s, [(r, 0.0) for r in lin(0, R_OUT, 5)], [(0, -1)] * 5)                 # outer bottom
    revolve(s, [(R_OUT, y) for y in lin(0, HEIGHT, 9)], [(1, 0)] * 9)               # outer wall
    mid, half = (R_OUT + R_IN) / 2, (R_OUT - R_IN) / 2                              # rounded rim
    rim = [math.pi * k / 8 for k in range(9)]
    revolve(s, [(mid + half * math.cos(t), HEIGHT + half * math.sin(t)) for t in rim],
            [(math.cos(t), math.sin(t)) for t in rim])
    revolve(s, [(R_IN, y) for y in lin(HEIGHT, FLOOR, 9)], [(-1, 0)] * 9)           # inner wall
    revolve(s, [(r, FLOOR) for r in lin(R_IN, 0, 5)], [(0, 1)] * 5)                 # inner floor
    return s


def mug_handle():
    """A C-shaped tube of elliptical section on the +x side; its ends sit inside the wall."""
    a, b_in, b_z, yc, phi0 = 24.0, 3.5, 6.0, 50.0, math.radians(62)
    xc = (R_OUT + R_IN) / 2 - a * math.cos(phi0)
    phi = np.linspace(-phi0, phi0, 25)
    psi = np.linspace(0, 2 * math.pi, 17)
    psi[-1] = 0.0
    P, Ps = np.meshgrid(phi, psi, indexing="ij")
    er = np.stack([np.cos(P), np.sin(P), np.zeros_like(P)], -1)
    ez = np.array([0.0, 0.0, 1.0])
    centre = np.stack([xc + a * np.cos(P), yc + a * np.sin(P), np.zeros_like(P)], -1)
    pts = centre + b_in * np.cos(Ps)[..., None] * er + b_z * np.sin(Ps)[..., None] * ez
    nrm = np.cos(Ps)[..., None] / b_in * er + np.sin(Ps)[..., None] / b_z * ez
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    s = Surface()
    s.grid(pts, nrm)
    return s


def rounded(surface):
    pos = np.round(np.asarray(surface.pos, np.float64), 4).astype("<f4")
    nrm = np.asarray(surface.nrm, np.float64)
    nrm = np.round(nrm / np.linalg.norm(nrm, axis=1, keepdims=True), 6).astype("<f4")
    return pos, nrm, np.asarray(surface.tri, "<u2")


def write_glb(path, prims):
    """prims: [(name, pos, nrm, tri)] -> one mesh, one node, a GLB with one buffer."""
    blob, views, accessors, primitives = b"", [], [], []

    def add(arr, target, acc):
        nonlocal blob
        blob += b"\0" * (-len(blob) % 4)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": arr.nbytes, "target": target})
        blob += arr.tobytes()
        acc["bufferView"] = len(views) - 1
        accessors.append(acc)
        return len(accessors) - 1

    for _, pos, nrm, tri in prims:
        p = add(pos, 34962, {"componentType": 5126, "count": len(pos), "type": "VEC3",
                             "min": [float(v) for v in pos.min(0)], "max": [float(v) for v in pos.max(0)]})
        n = add(nrm, 34962, {"componentType": 5126, "count": len(nrm), "type": "VEC3"})
        i = add(tri.reshape(-1), 34963, {"componentType": 5123, "count": tri.size, "type": "SCALAR"})
        primitives.append({"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "mode": 4})
    blob += b"\0" * (-len(blob) % 4)
    doc = {"asset": {"version": "2.0", "generator": "VTLoc examples/make_examples.py"},
           "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "mug"}],
           "meshes": [{"name": "mug", "primitives": primitives}],
           "buffers": [{"byteLength": len(blob)}], "bufferViews": views, "accessors": accessors,
           "extras": {"units": "mm", "up": "+y"}}
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    out = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(blob))
    out += struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
    path.write_bytes(out)


def read_press_frames(path):
    """press_imgs (49 x 120 x 160 x 3 uint8) from the safetensors file, without torch, as RGB: the
    file keeps its source's channel order, OpenCV's BGR (its __metadata__["channel_order"])."""
    buf = path.read_bytes()
    (n,) = struct.unpack("<Q", buf[:8])
    e = json.loads(buf[8:8 + n])["press_imgs"]
    b, end = e["data_offsets"]
    bgr = np.frombuffer(buf, np.uint8, end - b, 8 + n + b).reshape(e["shape"])
    return np.ascontiguousarray(bgr[..., ::-1])


def nearest_vertex(pos, nrm, target):
    i = int(np.argmin(np.linalg.norm(pos.astype(np.float64) - target, axis=1)))
    return [float(v) for v in pos[i]], [float(v) for v in nrm[i]]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gelsight", type=Path, default=DEFAULT_GELSIGHT)
    args = ap.parse_args()

    body, handle = rounded(mug_body()), rounded(mug_handle())
    write_glb(HERE / "mug.glb", [("body", *body), ("handle", *handle)])
    pos = np.concatenate([body[0], handle[0]])
    nrm = np.concatenate([body[1], handle[1]])

    def on_wall(deg, y, r=R_OUT):
        t = math.radians(deg)
        return np.array([r * math.cos(t), y, r * math.sin(t)])

    # (frame index, where on the mug, target near which the contact vertex is taken)
    touches = [
        (2, "outer wall, opposite the handle", on_wall(180, 47.5)),
        (6, "outside of the handle", np.array([54.2, 50.0, 0.0])),
        (21, "top of the rim, a quarter turn from the handle", on_wall(90, HEIGHT + 2.0, 38.0)),
    ]
    frames = read_press_frames(args.gelsight)
    candidates = []
    for k, (frame, where, target) in enumerate(touches, 1):
        p, n = nearest_vertex(pos, nrm, target)
        candidates.append(p)
        Image.fromarray(np.ascontiguousarray(frames[frame])).save(HERE / f"touch_{k:02d}.png", optimize=True)
        (HERE / f"touch_{k:02d}.json").write_text(json.dumps({
            "object": "mug.glb",
            "tactile": f"touch_{k:02d}.png",
            "contact": p,
            "contact_normal": n,
            "where": where,
            "units": "mm",
            "frame": f"press_imgs[{frame}] of objectfolder_gelsight_calib.safetensors (ObjectFolder 2.0, CC BY 4.0)",
            "note": "a real GelSight frame of a 4 mm ball pressed into the gel, NOT taken on this mug; "
                    "the contact point is the example's ground truth, not a measurement",
        }, indent=2) + "\n")
    # Nine more candidates spread over the mug (the paper uses 9-15 per object).
    for target in [on_wall(0, 15), on_wall(90, 47.5), on_wall(270, 80), on_wall(135, 20), on_wall(315, 60),
                   np.array([0.0, 0.0, 0.0]), on_wall(0, 80, R_IN), on_wall(200, FLOOR + 40, R_IN),
                   np.array([0.0, FLOOR, 0.0])]:
        candidates.append(nearest_vertex(pos, nrm, target)[0])
    # The column names are a comment, not a header line, so that weights_tools/inputs.py reads it too.
    lines = ["# candidate contact points on mug.glb (mm); the first three are the true contacts of touch_01..03",
             "# x,y,z"] + [",".join(f"{v + 0.0:.4f}" for v in c) for c in candidates]
    (HERE / "mug_candidates.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
