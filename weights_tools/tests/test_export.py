"""export: weight files, round trips, checkpoints with renamed keys."""

import json
import os
import struct
import subprocess
import sys

import pytest
import torch

from weights_tools import config, export, model, safetensors_io

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The CLI, run once as a user would, from the repository root."""
    path = tmp_path_factory.mktemp("export") / "tiny.safetensors"
    subprocess.run([sys.executable, "-m", "weights_tools.export", "--config", "vtloc-tiny",
                    "--seed", "0", "-o", str(path)], cwd=ROOT, check=True, capture_output=True)
    return path


def test_round_trip_bit_exact(exported):
    ref = export.random_model(config.named("vtloc-tiny"), 0).state_dict()
    tensors, meta = safetensors_io.load(exported)
    assert set(tensors) == set(ref)
    for k, v in ref.items():
        want = torch.float32 if v.is_floating_point() else torch.int64
        assert tensors[k].dtype == want, k
        assert torch.equal(tensors[k], v), k
    assert meta["format"] == "pt"
    assert json.loads(meta["vtloc.config"]) == config.named("vtloc-tiny")
    again = model.load(exported).state_dict()
    assert all(torch.equal(again[k], v) for k, v in ref.items())


def test_file_header(exported):
    buf = exported.read_bytes()
    (n,) = struct.unpack("<Q", buf[:8])
    assert (8 + n) % 8 == 0
    header = json.loads(buf[8:8 + n])
    assert header["gma.weight"]["shape"] == [32, 32, 8]
    assert header["tactile.backbone.bn1.num_batches_tracked"]["dtype"] == "I64"
    assert header["point.sa1.conv_blocks.0.0.weight"] == {
        "dtype": "F32", "shape": [16, 6, 1, 1],
        "data_offsets": header["point.sa1.conv_blocks.0.0.weight"]["data_offsets"]}


def test_batchnorm_statistics_are_randomised(exported):
    t, _ = safetensors_io.load(exported)
    bns = [k[:-len(".running_var")] for k in t if k.endswith(".running_var")]
    assert len(bns) == 12 + 9  # tiny ResNet: stem + 2 + 3 + 3 + 3; point net: 3 stages x 3
    for b in bns:
        assert not torch.allclose(t[b + ".running_var"], torch.ones_like(t[b + ".running_var"]))
        assert float(t[b + ".running_mean"].abs().max()) > 0
        assert not torch.allclose(t[b + ".weight"], torch.ones_like(t[b + ".weight"]))
        assert float(t[b + ".bias"].abs().max()) > 0


def test_seed_changes_weights():
    a = export.random_model(config.named("vtloc-tiny"), 0).state_dict()
    b = export.random_model(config.named("vtloc-tiny"), 1).state_dict()
    assert not torch.equal(a["ilu.convz.weight"], b["ilu.convz.weight"])


def test_checkpoint_with_renames(tmp_path):
    src = export.random_model(config.named("vtloc-mcr-tiny"), 3).state_dict()
    # a differently named model: DataParallel prefix, other top-level names, an extra head
    ckpt = {"module.visual." + k[len("tactile."):] if k.startswith("tactile.") else "module." + k: v
            for k, v in src.items()}
    ckpt["module.aux.weight"] = torch.zeros(2)
    torch.save({"state_dict": ckpt, "epoch": 3}, tmp_path / "ckpt.pt")
    out = tmp_path / "w.safetensors"
    rc = export.main(["--config", "vtloc-mcr-tiny", "--checkpoint", str(tmp_path / "ckpt.pt"),
                      "--rename", "module.visual.=tactile.", "--rename", "module.=",
                      "--drop", "aux.", "-o", str(out)])
    assert rc == 0
    t, _ = safetensors_io.load(out)
    assert set(t) == set(src) and all(torch.equal(t[k], v) for k, v in src.items())
    # a plain state_dict works too, and f16 storage is accepted by the loader
    torch.save(src, tmp_path / "plain.pt")
    assert export.main(["--config", "vtloc-mcr-tiny", "--checkpoint", str(tmp_path / "plain.pt"),
                        "--dtype", "f16", "-o", str(out)]) == 0
    half, _ = safetensors_io.load(out)
    assert half["mcr.decoder.0.weight"].dtype == torch.float16
    assert torch.equal(model.load(out).state_dict()["mcr.decoder.0.weight"],
                       src["mcr.decoder.0.weight"].half().float())


def test_checkpoint_mismatch_is_reported(tmp_path, capsys):
    src = export.random_model(config.named("vtloc-mcr-tiny"), 3).state_dict()
    torch.save({"net." + k: v for k, v in src.items()}, tmp_path / "ckpt.pt")
    rc = export.main(["--config", "vtloc-mcr-tiny", "--checkpoint", str(tmp_path / "ckpt.pt"),
                      "-o", str(tmp_path / "w.safetensors")])
    assert rc == 2 and "missing" in capsys.readouterr().err


def test_custom_config_json(tmp_path):
    cfg = config.named("vtloc-tiny")
    cfg.update(name="custom", C=8, gma=None)
    (tmp_path / "c.json").write_text(json.dumps(cfg))
    out = tmp_path / "w.safetensors"
    assert export.main(["--config-json", str(tmp_path / "c.json"), "-o", str(out)]) == 0
    m = model.load(out)
    assert m.cfg["name"] == "custom" and not m.has("gma") and m.tactile.mlp[2].out_features == 8
