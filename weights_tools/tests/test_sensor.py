"""The config's optional sensor section and the frame rescale before the crop
(tactile.rescale): schema, sizes, exact cases, and export/train round trips."""

import copy
import json
import subprocess
import sys

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from conftest import ROOT
from fake_dataset import make_dataset
from weights_tools import config, eval as eval_mod, golden, model, synthetic, train
from weights_tools.tactile import preprocess, rescale, rescaled_size, sensor_rescale

SENSOR = {"mm_per_px": 0.1245, "height": 120, "width": 160}


# ---------------------------------------------------------------- schema

def test_named_configs_record_the_synthetic_sensor():
    for name in ("vtloc-lite", "vtloc-lite-xyz", "mcr-lite", "vtloc-tiny-sensor"):
        assert config.named(name)["sensor"] == SENSOR
    for name in ("vtloc-r18", "vtloc-mcr", "vtloc-tiny", "vtloc-mcr-tiny"):
        assert "sensor" not in config.named(name)
        assert '"sensor"' not in config.to_json(config.named(name))  # old files stay byte for byte


def test_sensor_schema():
    base = config.named("vtloc-tiny")
    cfg = dict(base, sensor={"width": 640, "mm_per_px": 1, "height": 480})
    out = config.canonical(cfg)
    assert list(out)[-1] == "sensor" and out["sensor"] == {"mm_per_px": 1.0, "height": 480, "width": 640}
    assert "sensor" not in config.canonical(dict(base, sensor=None))
    for bad in ({"mm_per_px": 0, "height": 1, "width": 1}, {"mm_per_px": -1.0, "height": 1, "width": 1},
                {"mm_per_px": float("nan"), "height": 1, "width": 1}, {"mm_per_px": True, "height": 1, "width": 1},
                {"mm_per_px": 0.1, "height": 0, "width": 1}, {"mm_per_px": 0.1, "height": 1},
                {"mm_per_px": 0.1, "height": 1, "width": 1, "dpi": 3}, [0.1, 1, 1]):
        with pytest.raises(ValueError, match="sensor"):
            config.canonical(dict(base, sensor=bad))


def test_tiny_sensor_has_the_tiny_tensors():
    a = model.VTLoc(config.named("vtloc-tiny")).state_dict()
    b = model.VTLoc(config.named("vtloc-tiny-sensor")).state_dict()
    assert {k: v.shape for k, v in a.items()} == {k: v.shape for k, v in b.items()}


def test_export_and_load_keep_the_sensor(tmp_path):
    w = tmp_path / "w.safetensors"
    r = subprocess.run([sys.executable, "-m", "weights_tools.export", "--config", "vtloc-tiny-sensor",
                        "--seed", "0", "-o", str(w)], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert model.load(str(w)).cfg["sensor"] == SENSOR
    cfg = dict(config.named("vtloc-tiny"), sensor={"mm_per_px": 0.05, "height": 240, "width": 320})
    j = tmp_path / "c.json"
    j.write_text(json.dumps(cfg))
    r = subprocess.run([sys.executable, "-m", "weights_tools.export", "--config-json", str(j),
                        "--seed", "0", "-o", str(w)], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert model.load(str(w)).cfg["sensor"]["mm_per_px"] == 0.05


def test_training_exports_the_sensor(tmp_path):
    data = make_dataset(str(tmp_path / "data"), n_train=4, n_extra=1)
    train.run(train.parse_args(["--config", "vtloc-tiny-sensor", "--data", data, "--out",
                                str(tmp_path / "run"), "--steps", "2", "--batch", "4", "--threads", "1"]))
    assert model.load(str(tmp_path / "run" / "model.safetensors")).cfg["sensor"] == SENSOR


# ---------------------------------------------------------------- rescale

def _frame(h, w, seed=0):
    return torch.randint(0, 256, (h, w, 3), generator=torch.Generator().manual_seed(seed), dtype=torch.uint8)


def test_sizes_round_half_up():
    assert rescaled_size(120, 0.083, 0.1245) == 80 and rescaled_size(160, 0.083, 0.1245) == 107
    assert rescaled_size(120, 0.166, 0.1245) == 160 and rescaled_size(160, 0.166, 0.1245) == 213
    assert rescaled_size(3, 1.0, 2.0) == 2  # 1.5 -> 2
    assert rescaled_size(240, 0.1245 / 2, 0.1245) == 120


def test_equal_pixel_sizes_change_nothing():
    f = _frame(30, 40)
    assert rescale(f, 0.2, 0.2) is not None and torch.equal(rescale(f, 0.2, 0.2), f)


def test_double_resolution_replica_gives_the_frame_back():
    """Each pixel as a 2x2 block at half the pixel size: the area average of a
    block (weights exactly 1/2 per axis) is that pixel, bit for bit."""
    f = _frame(120, 160, 1)
    big = f.repeat_interleave(2, 0).repeat_interleave(2, 1)
    assert torch.equal(rescale(big, 0.1245 / 2, 0.1245), f)


def test_shrink_by_an_integer_is_a_box_average():
    f = _frame(60, 90, 2)
    want = F.avg_pool2d(f.permute(2, 0, 1).double()[None], 3)[0].permute(1, 2, 0)
    got = rescale(f, 1.0, 3.0).double()
    assert got.shape == want.shape
    assert (got - want).abs().max() <= 0.5 + 1e-9  # rounding to uint8 only


def test_enlarge_by_two_is_pytorch_bilinear():
    f = _frame(40, 50, 3)
    want = F.interpolate(f.permute(2, 0, 1).double()[None], scale_factor=2, mode="bilinear",
                         align_corners=False)[0].permute(1, 2, 0)
    got = rescale(f, 2.0, 1.0).double()
    assert got.shape == want.shape
    assert (got - want).abs().max() <= 0.5 + 1e-9


def test_smooth_scene_at_two_resolutions():
    """One smooth scene sampled at 0.1245 mm and at 0.06225 mm pixels: after the
    rescale the network inputs differ by at most one grey level (each frame is
    rounded to uint8 once, the rescaled one twice) over the ImageNet std."""
    def scene(h, w, mm):
        v = (torch.arange(h, dtype=torch.float64) - (h - 1) / 2) * mm
        u = (torch.arange(w, dtype=torch.float64) - (w - 1) / 2) * mm
        base = 128 + 90 * torch.sin(u[None, :] / 2.0) * torch.cos(v[:, None] / 1.5)
        img = torch.stack([base, base.flip(1), 255 - base], dim=-1)
        return torch.floor(img + 0.5).clamp(0, 255).to(torch.uint8)
    small, big = scene(120, 160, 0.1245), scene(240, 320, 0.06225)
    cfg = config.named("vtloc-lite")
    t = cfg["tactile"]
    a = preprocess(small, t["crop"], t["in_size"], torch.float64)
    b = preprocess(sensor_rescale(big, cfg, 0.06225), t["crop"], t["in_size"], torch.float64)
    assert (a - b).abs().max() <= 1.01 / 255 / 0.224


def test_rescale_errors():
    f = _frame(20, 20)
    with pytest.raises(ValueError, match="has no sensor pixel size in its config; cannot rescale"):
        sensor_rescale(f, config.named("vtloc-tiny"), 0.1)
    for bad in (0, -0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="finite number > 0"):
            sensor_rescale(f, config.named("vtloc-tiny-sensor"), bad)
    assert torch.equal(sensor_rescale(f, config.named("vtloc-tiny"), None), f)


def test_golden_cli_mm_per_px(tmp_path):
    out = tmp_path / "g.safetensors"
    w = tmp_path / "w.safetensors"
    model.save(model.VTLoc(config.named("vtloc-tiny-sensor")), str(w))
    t, meta, _ = golden.make(str(w), synthetic_tactile=0, synthetic_cloud=0, mm_per_px=0.083)
    assert tuple(t["tactile.rescaled"].shape) == (80, 107, 3) and meta["mm_per_px"] == "0.083"
    r = subprocess.run([sys.executable, "-m", "weights_tools.golden", "--weights",
                        "weights_tools/goldens/vtloc-tiny.safetensors", "--synthetic-tactile", "0",
                        "--synthetic-cloud", "0", "--mm-per-px", "0.1", "-o", str(out)],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "has no sensor pixel size in its config; cannot rescale" in r.stderr


def test_eval_pixel_size_choice():
    lite, tiny = config.named("vtloc-lite"), config.named("vtloc-tiny")
    assert eval_mod.frame_mm_per_px(lite, {"mm_per_px": 0.1245}) is None
    assert eval_mod.frame_mm_per_px(lite, {"mm_per_px": 0.06}) == 0.06
    assert eval_mod.frame_mm_per_px(lite, {}) is None
    assert eval_mod.frame_mm_per_px(tiny, {"mm_per_px": 0.06}) is None
    assert eval_mod.frame_mm_per_px(lite, {"mm_per_px": 0.1245}, 0.2) == 0.2
    with pytest.raises(ValueError):
        eval_mod.frame_mm_per_px(lite, {}, -1.0)
