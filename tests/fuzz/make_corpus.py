#!/usr/bin/env python3
"""Writes the seed corpus of every fuzz target into tests/fuzz/corpus/<target>/
(small, valid inputs the readers accept, so the fuzzer starts past the magic
numbers). Run from anywhere: python3 tests/fuzz/make_corpus.py"""
import json
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "corpus")

TINY_CONFIG = {
    "name": "seed", "C": 4, "K": 2,
    "tactile": {"crop": 16, "in_size": 8, "widths": [2, 2, 2, 2], "blocks": [1, 1, 1, 1], "mlp": [4]},
    "point": {"n_points": 8, "use_normals": True,
              "sa": [{"npoint": 4, "radii": [0.5], "nsample": [2], "mlps": [[2, 4]]}],
              "group_all_mlp": [4], "mlp": []},
    "gma": {"n_points": 4, "channels": 2, "decoder": [2]},
    "ilu": {"iters": 2, "head_hidden": 4}, "head": "ilu", "mcr": None,
    "sensor": {"mm_per_px": 0.1245, "height": 120, "width": 160},
}


def put(target, name, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def safetensors(tensors, meta):
    header, blob = {"__metadata__": meta}, b""
    for name, (dtype, shape, raw) in tensors.items():
        header[name] = {"dtype": dtype, "shape": shape, "data_offsets": [len(blob), len(blob) + len(raw)]}
        blob += raw
    h = json.dumps(header).encode()
    return struct.pack("<Q", len(h)) + h + blob


def png(w, h, channels, depth, pixels):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    colour = {1: 0, 3: 2}[channels]
    raw = b"".join(b"\0" + pixels[y * w * channels * depth // 8:(y + 1) * w * channels * depth // 8] for y in range(h))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def main():
    cfg = json.dumps(TINY_CONFIG)
    put("config", "tiny.json", cfg)
    put("config", "mcr.json", json.dumps(dict(TINY_CONFIG, head="mcr", ilu=None, mcr={"hidden": [4]}, gma=None)))
    f32 = struct.pack("<6f", 1, -2, 0.5, 3, 0, 1e-3)
    put("safetensors", "one_tensor.safetensors",
        safetensors({"w": ("F32", [2, 3], f32)}, {"vtloc.config": cfg}))
    put("safetensors", "f16_i64.safetensors",
        safetensors({"h": ("F16", [2], struct.pack("<2e", 1.5, -2)), "n": ("I64", [1], struct.pack("<q", 7))},
                    {"vtloc.config": cfg, "note": "x"}))

    tri_off = "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2 3\n"
    tri_obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1 3 4\n"
    tri_ply = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
               "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2 3\n")
    stl_ascii = ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                 "endfacet\nendsolid t\n")
    stl_bin = b"\0" * 80 + struct.pack("<I", 1) + struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    idx = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    gltf = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "buffers": [{"byteLength": len(pos) + len(idx)}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                            {"buffer": 0, "byteOffset": len(pos), "byteLength": 6}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}
    js = json.dumps(gltf).encode()
    js += b" " * (-len(js) % 4)
    binchunk = pos + idx
    glb = (struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(binchunk)) +
           struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(binchunk), 0x004E4942) + binchunk)
    for i, (name, data) in enumerate([("tri.ply", tri_ply), ("tri.obj", tri_obj), ("tri.off", tri_off),
                                      ("tri_ascii.stl", stl_ascii), ("tri.gltf", json.dumps(gltf)),
                                      ("tri.glb", glb)]):
        put("mesh", name, bytes([i]) + (data if isinstance(data, bytes) else data.encode()))
    put("mesh", "tri_binary.stl", bytes([3]) + stl_bin)

    pts = "".join(f"{x} {y} {z} 0 0 1\n" for x, y, z in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0.5)] * 20)
    ply_pts = ("ply\nformat ascii 1.0\nelement vertex 80\nproperty float x\nproperty float y\nproperty float z\n"
               "property float nx\nproperty float ny\nproperty float nz\nend_header\n" + pts)
    ply_bin = ("ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
               "property float z\nend_header\n").encode() + struct.pack("<6f", 0, 0, 0, 1, 2, 3)
    pcd = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n"
           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n0 0 0\n1 0 0\nnan nan nan\n")
    pcd_bin = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
               "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n").encode() + struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    put("points", "normals.ply", b"\0" + ply_pts.encode())
    put("points", "binary.ply", b"\0" + ply_bin)
    put("points", "ascii.pcd", b"\1" + pcd.encode())
    put("points", "binary.pcd", b"\1" + pcd_bin)
    put("points", "rows.xyz", b"\2" + pts.encode())
    put("points", "rows.csv", b"\3" + ("x,y,z\n" + "".join(f"{i},{i % 3},{i % 5}\n" for i in range(70))).encode())

    rgb = bytes((x * 37 + y * 11 + c * 5) % 256 for y in range(12) for x in range(16) for c in range(3))
    put("image", "rgb_16x12.png", b"\0" + png(16, 12, 3, 8, rgb))
    depth = b"".join(struct.pack(">H", 400 + x + y) for y in range(6) for x in range(8))
    put("image", "depth_8x6.png", b"\1" + png(8, 6, 1, 16, depth))
    # JPEG (baseline, progressive, grey) through PIL's libjpeg; a bottom-up 24-bit BMP by hand.
    import io
    from PIL import Image
    frame = Image.frombytes("RGB", (16, 12), rgb)
    for name, im, opts in (("baseline.jpg", frame, {"quality": 90}), ("progressive.jpg", frame, {"progressive": True}),
                           ("grey.jpg", frame.convert("L"), {})):
        buf = io.BytesIO()
        im.save(buf, "JPEG", **opts)
        put("image", name, b"\0" + buf.getvalue())
    bmp_pixels = b"".join(bytes(rgb[(y * 16 + x) * 3 + c] for x in range(16) for c in (2, 1, 0)) for y in reversed(range(12)))
    put("image", "rgb_16x12.bmp", b"\0" + b"BM" + struct.pack("<IHHI", 54 + len(bmp_pixels), 0, 0, 54) +
        struct.pack("<IiiHHIIiiII", 40, 16, 12, 1, 24, 0, len(bmp_pixels), 2835, 2835, 0, 0) + bmp_pixels)

    small = os.path.join(HERE, "..", "..", "build", "tests", "synth", "out", "small")
    parts = []
    for name in ("dataset.json", "objects/sphere/object.json", "objects/sphere/points.csv",
                 "objects/sphere/touches.csv"):
        with open(os.path.join(small, name)) as f:
            text = f.read()
        if name == "dataset.json":  # one object, named as the harness lays it out
            d = json.loads(text)
            d["objects"] = [dict(d["objects"][[o["name"] for o in d["objects"]].index("sphere")], name="o")]
            text = json.dumps(d)
        parts.append(text)
    put("dataset", "one_object.txt", "\n=====\n".join(parts))
    touches_corpus()
    calibration_corpus()
    codebook_corpus()
    device_profile_corpus()


def codebook_corpus():
    # fuzz_codebook.cpp's two samples (on z = 0, looking down), their 27 x 27 maps (default options).
    samples = [0, 0, 0, 0, 0, 1, 1, 0, 0, 3, 0, 0, 0, 0, 1, 1, 0, 0]
    heights = [0.01 * (i % 27) for i in range(2 * 27 * 27)]
    meta = {"format": "vtloc-codebook/1", "cell_mm": "1", "splat_mm": "0.75", "cap_mm": "8", "facing": "0.3",
            "reach_mm": "12.5", "G": "27"}
    put("codebook", "two_samples.safetensors", safetensors({
        "heights": ("F32", [2, 27 * 27], struct.pack(f"<{len(heights)}f", *heights)),
        "samples": ("F32", [2, 9], struct.pack("<18f", *samples))}, meta))


def touches_corpus():
    rot = [[0.9396926207859084, -0.3420201433256687, 0, 12.0], [0.3420201433256687, 0.9396926207859084, 0, 1.5],
           [0, 0, 1, -0.5], [0, 0, 0, 1]]
    put("touches", "relative.json", json.dumps({
        "format": "vtloc-touches/2", "motion": "relative", "object": "o.ply", "object_diameter_mm": 99,
        "touches": [{"tactile": "a.png", "contact": [1, 2, 3]}, {"tactile": "b.png", "motion": rot},
                    {"tactile": "c.png", "motion": {"Q": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "q": [0, 10, 0]}}]}))
    put("touches", "flange.json", json.dumps({
        "format": "vtloc-touches/2", "motion": "flange", "tool": rot,
        "touches": [{"tactile": "a.png", "flange": rot}, {"tactile": "b.png", "flange": rot}]}))


def calibration_corpus():
    # An 8 x 8 sensor with a 2-bin table: without presses, and with one (a user's own sensor
    # may ship none).
    f32 = lambda n, v=0.5: struct.pack(f"<{n}f", *([v] * n))
    tables = {c: ("F32", [2, 2, 6], f32(24, 0.1)) for c in ("poly_r", "poly_g", "poly_b")}
    base = dict(tables, real_bg=("F32", [8, 8, 3], f32(192, 100.0)), depth_bg=("F32", [8, 8], f32(64, 0.0)))
    put("calibration", "no_presses.safetensors", safetensors(base, {"sensor": "pixmm=0.2"}))
    presses = dict(base, press_imgs=("U8", [1, 8, 8, 3], bytes(range(192))), press_f0=("U8", [8, 8, 3], bytes(192)),
                   press_center=("F32", [1, 2], struct.pack("<2f", 4.0, 3.5)), press_radius=("I32", [1], struct.pack("<i", 3)))
    put("calibration", "one_press.safetensors", safetensors(presses, {"sensor": "pixmm=0.1245"}))


def device_profile_corpus():
    # The shipped profiles are valid seeds as they are.
    shipped = os.path.join(HERE, "..", "..", "bench", "device_profiles")
    for name in sorted(os.listdir(shipped)):
        with open(os.path.join(shipped, name), "rb") as f:
            put("device_profile", name, f.read())


if __name__ == "__main__":
    main()
