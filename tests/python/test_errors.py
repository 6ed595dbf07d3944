"""Bad arrays and arguments: a vtloc.Error whose one-line message names the
argument and what was wrong; never a crash, never a silent conversion."""

import os

import numpy as np
import pytest

import vtloc


def expect(fragment, fn, *args, **kwargs):
    with pytest.raises(vtloc.Error) as e:
        fn(*args, **kwargs)
    msg = str(e.value)
    assert fragment in msg and "\n" not in msg, msg


def test_bad_images(tiny, mug, touch):
    im = vtloc.load_tactile_image(touch)
    expect("expected an H x W x 3 uint8 RGB array or a path, got a float32 array of shape (120, 160, 3)",
           tiny.localize, mug, im.astype(np.float32))
    expect("got a uint8 array of shape (120, 160)", tiny.localize, mug, im[:, :, 0].copy())
    expect("got a uint8 array of shape (120, 160, 4)", tiny.localize, mug,
           np.concatenate([im, im[:, :, :1]], axis=2))
    expect("is not C-contiguous", tiny.localize, mug, im[:, ::2])
    expect("expected a numpy array, got list", tiny.localize, mug, [im.tolist()])
    expect("image[1]: expected", tiny.localize, mug, [im, im.astype(np.int16)])
    expect("the list of frames is empty", tiny.localize, mug, [])
    expect("smallest accepted", tiny.localize, mug, np.zeros((4, 4, 3), np.uint8))
    expect("nosuch.png", tiny.localize, mug, os.path.join(os.path.dirname(touch), "nosuch.png"))


def test_bad_clouds(tiny, mug):
    cloud = mug.cloud.copy()
    line = np.zeros((40, 3), np.float32)
    line[:, 0] = np.arange(40)
    expect("collinear or identical", tiny.encode_object, line)
    expect("at least 16 points", tiny.encode_object, cloud[:5, :3].copy())
    expect("expected a float32 or float64 array of shape (N, 6) (x y z nx ny nz; or (N, 3) without normals)",
           tiny.encode_object, cloud.astype(np.int32))
    expect("got a float32 array of shape (128, 5)", tiny.encode_object, cloud[:, :5].copy())
    nan = cloud.copy()
    nan[17, 1] = np.nan
    expect("row 17 holds NaN or inf", tiny.encode_object, nan)
    inf = cloud.astype(np.float64)
    inf[3, 4] = np.inf
    expect("row 3 holds NaN or inf", tiny.encode_object, inf)
    expect("the cloud is empty", tiny.encode_object, np.zeros((0, 6), np.float32))
    expect("is not C-contiguous", tiny.encode_object, np.asfortranarray(cloud))
    zero = cloud.copy()
    zero[5, 3:] = 0
    expect("normal", tiny.encode_object, zero)
    expect("candidates: expected a float32 or float64 array of shape (N, 3)", tiny.encode_object, cloud,
           cloud[:, :2].copy())
    expect("backend must be 'gpu' or 'cpu', got 'tpu'", tiny.encode_object, cloud, None, "tpu")


def test_bad_options(tiny, mug, touch):
    expect("iters must be in 0..64", tiny.localize, mug, touch, iters=65)
    expect("K must be in 1..256, got 100000", tiny.localize, mug, touch, top_k=100000)
    expect("larger than the candidate set", tiny.localize, mug, touch, top_k=200)
    expect("symmetry: expected a vtloc.Symmetry", tiny.localize, mug, touch, symmetry=(0, 0, 1))
    expect("mm_per_px: expected a number", tiny.localize, mug, touch, mm_per_px="0.1")
    expect("no sensor pixel size", tiny.localize, mug, touch, mm_per_px=0.1)
    expect("axis_dir: expected 3 numbers", vtloc.Symmetry, (0, 0, 0), (0, 1), 2)

    expect("heat: expected a 1-D float32 or float64 array", vtloc.write_heatmap_ply, "/tmp/x.ply", mug,
           np.zeros((2, 2), np.float32))


def test_bad_files(ctx, tmp_path):
    bad = tmp_path / "bad.safetensors"
    bad.write_bytes(b"\x05\x00\x00\x00\x00\x00\x00\x00{abc}")
    expect("bad.safetensors", vtloc.Model, ctx, str(bad))
    expect("nosuch", vtloc.inspect_model, str(tmp_path / "nosuch.safetensors"))
    expect("nosuch", vtloc.Context, "nosuch-device-name")


def test_bad_tracker_inputs(ctx, root):
    tr = vtloc.Tracker(ctx, os.path.join(root, "examples", "mug.glb"), hypotheses=20000)
    expect("motion: expected a float32 or float64 4 x 4 array", tr.add_touch, np.zeros((3, 3)))
    expect("touch 1: the first touch has no previous one", tr.add_touch, np.eye(4))
    tr.add_touch()
    bad = np.eye(4)
    bad[0, 0] = 2
    expect("touch 2's motion: the 3x3 part is not a rotation", tr.add_touch, bad)
    nan = np.eye(4)
    nan[1, 3] = np.nan
    expect("NaN or inf", tr.add_touch, nan)
    last = np.eye(4)
    last[3, 3] = np.inf  # named as such, not as a last row that is not 0 0 0 1
    expect("motion: row 3, column 3 holds NaN or inf", tr.add_touch, last)
    # A hop longer than the mug allows (a glitch, or an object file in other units than the robot's).
    far = np.eye(4)
    far[0, 3] = 1.01 * tr.max_hop
    expect("touch 2's motion: the sensor moves", tr.add_touch, far)
    expect("object_units", tr.check_motion, far, 2)
    far[0, 3] = 0.99 * tr.max_hop
    tr.check_motion(far, 2)
    expect("check_motion: touch 1 has no motion", tr.check_motion, far, 1)
    assert tr.touches == 1
    expect("needs a normal per point", vtloc.Tracker, ctx, np.zeros((10, 3), np.float32))
