"""The engine's image reader against PIL, which weights_tools reads frames with
(dataset.py, inputs.py): files PIL writes load to the pixels PIL decodes, bit
for bit, JPEG included (both use Debian's libjpeg-turbo), and the engine's own
PNGs read back in PIL unchanged."""

import os
import subprocess

import numpy as np
import pytest
from PIL import Image

import vtloc

RNG = np.random.default_rng(7)
# Smooth and noisy parts: JPEG's chroma upsampling and rounding both matter.
_Y, _X = np.mgrid[0:37, 0:53]
FRAME = np.clip(np.stack([_X * 4, _Y * 6, (_X + _Y) * 2], -1) + RNG.integers(0, 40, (37, 53, 3)), 0, 255).astype(np.uint8)


def _cases():
    rgb = Image.fromarray(FRAME)
    grey = rgb.convert("L")
    yield "rgb.png", rgb, {}
    yield "grey.png", grey, {}
    yield "grey_alpha.png", Image.merge("LA", (grey, grey.point(lambda v: 255 - v))), {}
    yield "rgba.png", rgb.convert("RGBA"), {}
    yield "palette.png", rgb.convert("P", palette=Image.ADAPTIVE, colors=37), {}
    yield "palette_trns.png", rgb.convert("P", palette=Image.ADAPTIVE, colors=16), {"transparency": 3}
    yield "bits1.png", grey.point(lambda v: 255 if v > 120 else 0).convert("1"), {}
    yield "interlaced.png", rgb, {"interlace": 1}
    yield "q90_420.jpg", rgb, {"quality": 90, "subsampling": 2}
    yield "q75_444.jpg", rgb, {"quality": 75, "subsampling": 0}
    yield "progressive.jpg", rgb, {"quality": 85, "progressive": True}
    yield "grey.jpg", grey, {"quality": 80}
    yield "rgb.bmp", rgb, {}
    yield "palette.bmp", rgb.convert("P", palette=Image.ADAPTIVE, colors=200), {}


@pytest.mark.parametrize("name,image,options", list(_cases()), ids=lambda v: v if isinstance(v, str) else "")
def test_files_pil_writes_load_as_pil_decodes_them(tmp_path, name, image, options):
    path = str(tmp_path / name)
    image.save(path, **options)
    with Image.open(path) as im:
        want = np.asarray(im.convert("RGB"))
    got = vtloc.load_tactile_image(path)
    assert got.shape == want.shape and got.dtype == np.uint8
    assert np.array_equal(got, want), f"{name}: {int(np.abs(got.astype(int) - want).max())} levels apart"


def test_the_engines_pngs_read_back_in_pil(cli, ctx, root, tmp_path):
    """`vtloc shape` writes a 16-bit height map and an 8-bit RGB picture: PIL reads the
    micrometres the Python reader computes for the same frame."""
    frame = os.path.join(root, "examples", "plate_test0_touch.png")
    subprocess.run([cli, "shape", "--tactile", frame, "--rendered", "--out", str(tmp_path)], check=True,
                   capture_output=True)
    reader = vtloc.GelShapeReader(ctx, mask_threshold=0.05, levels=2, coarse_iterations=30, iterations=10)
    depth = reader.read(frame)["depth_mm"]
    with Image.open(tmp_path / "height.png") as im:
        assert im.mode in ("I;16", "I")
        height = np.asarray(im, dtype=np.int64)
    assert height.shape == depth.shape and height.max() > 0
    want = np.clip(np.round(depth.astype(np.float64) * 1000), 0, 65535)
    assert np.abs(height - want).max() <= 1  # float32 depth, rounded to whole micrometres
    with Image.open(tmp_path / "shape.png") as im:
        assert im.mode == "RGB" and im.size[1] >= depth.shape[0]
