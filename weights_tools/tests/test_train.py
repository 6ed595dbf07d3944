"""train.py on a tiny fake dataset: pieces match the reference, the loss goes down,
resume continues exactly, the exported file loads back; the lite configs' sizes."""

import copy
import csv
import json
import os

import numpy as np
import pytest
import torch

from fake_dataset import make_dataset
from weights_tools import config, export, model, post, safetensors_io, train
from weights_tools.dataset import read_dataset
from weights_tools.tactile import preprocess


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    return make_dataset(str(tmp_path_factory.mktemp("ds") / "data"), n_train=10, n_extra=3)


@pytest.fixture(scope="module")
def tiny(data_dir):
    m = train.make_model(config.named("vtloc-tiny"), 0)
    return m, train.load_objects(m, read_dataset(data_dir))


def _args(data_dir, out, *extra):
    return ["--config", "vtloc-tiny", "--data", data_dir, "--out", str(out), "--batch", "4",
            "--threads", "1", *extra]


def test_split_by_contact(data_dir, tiny):
    _, objs = tiny
    ds = read_dataset(data_dir)
    assert [o.name for o in objs] == ["shape00", "shape01"]  # seen objects only
    for o in objs:
        split = {t.id: t.split for t in ds.object(o.name).touches}
        val = [o.ids[i] for i in o.val_index]
        assert len(val) == 1 and all(split[i] == "train" for i in val)
        assert all(split[i] in ("train", "extra") for i in o.ids)  # never a test touch
        assert not set(val) & set(o.ids[:o.n_train])
    # fixed by the object's name, not by the run's seed
    assert train.split_contacts(ds.objects[0]) == train.split_contacts(ds.objects[0])


def test_pieces_match_reference(tiny):
    m, objs = tiny
    o = objs[0]
    m.eval()
    with torch.no_grad():
        assert torch.equal(train.point_features(m.point, o.cloud, o.plan), m.point(o.cloud))
    want = torch.cat([preprocess(o.images[i].numpy(), 128, 40) for i in range(3)])
    assert torch.allclose(train.images_to_input(o.images[:3], m.cfg), want, atol=1e-6)
    # the augmented path samples crop + resize in one grid_sample: the same at angle 0
    x = o.images[:3].permute(0, 3, 1, 2).float() / 255
    for crop, size in ((128, 40), (120, 112), (117, 50)):
        ref = torch.cat([preprocess(o.images[i].numpy(), crop, size) for i in range(3)])
        got = train._normalise(train.rotated_crops(x, crop, size, torch.zeros(3)))
        assert torch.allclose(got, ref, atol=3e-5)
    aug = train.images_to_input(o.images[:3], m.cfg, torch.Generator().manual_seed(0))
    assert aug.shape == want.shape and not torch.allclose(aug, want)
    a, b = torch.randn(2, 20, 6, dtype=torch.float64), torch.randn(30, 6, dtype=torch.float64)
    got = train.chamfer_batch(a, b)
    assert torch.allclose(got, torch.stack([post.chamfer(a[i], b) for i in range(2)]))
    m.train()


def _batch_loss(m, o):
    """Training-mode loss on a fixed batch (on a copy: it updates BatchNorm statistics)."""
    with torch.no_grad():
        return float(train.losses(copy.deepcopy(m).train(), o, list(range(4)))[0])


def test_training_lowers_loss_and_resumes(data_dir, tiny, tmp_path):
    m0, objs = tiny
    before = _batch_loss(train.make_model(config.named("vtloc-tiny"), 0), objs[0])
    # uninterrupted: 24 steps
    full, step, _ = train.run(train.parse_args(_args(data_dir, tmp_path / "a", "--steps", "24")))
    assert step == 24
    assert _batch_loss(full, objs[0]) < before
    # interrupted after 10 steps, then resumed to the same budget: the same weights
    b = tmp_path / "b"
    train.run(train.parse_args(_args(data_dir, b, "--steps", "24", "--stop-after", "10")))
    assert torch.load(b / "checkpoint.pt")["step"] == 10 and not (b / "model.safetensors").exists()
    with pytest.raises(ValueError, match="--resume"):
        train.run(train.parse_args(_args(data_dir, b, "--steps", "24")))
    resumed, step, _ = train.run(train.parse_args(["--data", data_dir, "--out", str(b), "--resume",
                                                   "--threads", "1"]))
    assert step == 24
    sa, sb = full.state_dict(), resumed.state_dict()
    assert all(torch.allclose(sa[k].double(), sb[k].double(), atol=1e-6) for k in sa)
    with open(b / "log.csv") as f:
        steps = [int(r["step"]) for r in csv.DictReader(f)]
    assert steps == sorted(steps) and steps[-1] == 24 and 10 in steps
    with open(b / "log.csv") as f:
        last = list(csv.DictReader(f))[-1]
    assert float(last["val_nd"]) > 0

    # the exported file: loads into the reference, same tensors, provenance metadata
    path = str(b / "model.safetensors")
    back = model.load(path)
    ref = resumed.eval().state_dict()
    assert all(torch.equal(back.state_dict()[k], ref[k]) for k in ref)
    _, meta = safetensors_io.load(path)
    prov = json.loads(meta["vtloc.provenance"])
    assert prov["steps"] == 24 and prov["data_seed"] == 0 and prov["config"] == "vtloc-tiny"
    # the run's first command (interrupted at 10 steps), and the resume that finished it
    assert "--stop-after 10" in prov["command"] and "--resume" in prov["last_command"]
    assert [(o["name"], o["object_split"]) for o in prov["objects"]] == [
        ("shape00", "seen"), ("shape01", "seen"), ("shape02", "unseen")]
    assert prov["sensor"]["height"] == 120 and len(prov["git_commit"]) in (7, 40) or \
        prov["git_commit"] == "unknown"
    assert json.loads(meta["vtloc.config"]) == config.named("vtloc-tiny")
    # the checkpoint is also a valid export.py --checkpoint input
    assert export.main(["--config", "vtloc-tiny", "--checkpoint", str(b / "checkpoint.pt"),
                        "-o", str(tmp_path / "w.safetensors")]) == 0


def test_keep_best_keeps_and_exports_the_lowest_validation(data_dir, tmp_path):
    """--keep-best: best.pt is the checkpoint of the lowest validation ND in log.csv, a
    resumed run keeps the same one, and model-best.safetensors is its export."""
    # validation after every step; a large learning rate, so that the lowest is not the last
    run = ["--steps", "12", "--ckpt-minutes", "0", "--keep-best", "--lr", "0.01"]
    train.run(train.parse_args(_args(data_dir, tmp_path / "a", *run)))
    b = tmp_path / "b"
    train.run(train.parse_args(_args(data_dir, b, *run, "--stop-after", "5")))
    train.run(train.parse_args(["--data", data_dir, "--out", str(b), "--resume", "--threads", "1",
                                "--ckpt-minutes", "0"]))  # --keep-best comes from the checkpoint
    for d in (tmp_path / "a", b):
        with open(d / "log.csv") as f:
            rows = [(float(r["val_nd"]), int(r["step"])) for r in csv.DictReader(f) if r["val_nd"]]
        assert len(rows) == 12
        nd, step = min(rows, key=lambda r: (r[0], r[1]))
        assert step < 12 and torch.load(d / "best.pt")["step"] == step, rows  # the run ends elsewhere
        _, meta = safetensors_io.load(str(d / "model-best.safetensors"))
        prov = json.loads(meta["vtloc.provenance"])
        assert prov["steps"] == step and abs(prov["val_nd"] - nd) <= 1e-4
    ta, tb = torch.load(tmp_path / "a" / "best.pt")["state_dict"], torch.load(b / "best.pt")["state_dict"]
    assert all(torch.allclose(ta[k].double(), tb[k].double(), atol=1e-6) for k in ta)


def test_mcr_head_trains(data_dir, tmp_path):
    m, step, _ = train.run(train.parse_args(
        ["--config", "vtloc-mcr-tiny", "--data", data_dir, "--out", str(tmp_path), "--steps", "3",
         "--batch", "4", "--threads", "1"]))
    assert step == 3 and model.load(str(tmp_path / "model.safetensors")).cfg["head"] == "mcr"


@pytest.mark.parametrize("name", ["vtloc-lite", "vtloc-lite-xyz", "mcr-lite"])
def test_lite_configs(name):
    cfg = config.named(name)
    n = sum(v.numel() for k, v in model.VTLoc(cfg).state_dict().items()
            if not k.endswith("num_batches_tracked"))
    assert n * 4 <= 16 * 2**20  # F32 weight file of at most 16 MiB
    assert cfg["tactile"]["crop"] == 120 and cfg["point"]["use_normals"] == (name == "vtloc-lite")
    assert (cfg["head"] == "mcr") == (name == "mcr-lite")


def test_local_match_loss(tiny):
    """The training-only matching loss adds to the total, reaches both encoders,
    starts near chance (log of the centre count) and is off at weight 0."""
    m, objs = tiny
    m = copy.deepcopy(m).train()
    match = train.LocalMatch(m.cfg)
    idx = list(range(4))
    total, seq, rec, _, aux = train.losses(m, objs[0], idx, 1.0, match=match, mu=1.0)
    assert float(aux) > 0 and torch.isclose(total, seq + rec + aux)
    half = train.losses(m, objs[0], idx, 1.0, match=match, mu=0.5)[4]
    assert torch.isclose(half, 0.5 * aux)
    chance = np.mean([np.log(st["npoint"]) for st in m.cfg["point"]["sa"]])
    assert abs(float(aux) - chance) < 0.5
    aux.backward()
    for branch in (m.tactile, m.point):
        assert any(p.grad is not None and float(p.grad.abs().sum()) > 0 for p in branch.parameters())
    assert float(train.losses(m, objs[0], idx, 1.0, match=match, mu=0.0)[4]) == 0.0
    # never part of the exported model
    assert not any(k.startswith(("q.", "k.")) for k in m.state_dict())


def test_match_weight_recorded(data_dir, tmp_path):
    train.run(train.parse_args(_args(data_dir, tmp_path, "--steps", "3", "--match", "0", "--feature-scale", "0")))
    with open(tmp_path / "log.csv") as f:
        rows = list(csv.DictReader(f))
    assert all(r["loss_aux"] == "" for r in rows)
    _, meta = safetensors_io.load(str(tmp_path / "model.safetensors"))
    assert json.loads(meta["vtloc.provenance"])["match_weight"] == 0.0


def test_feature_scale_penalty(tiny):
    """Zero at unit RMS per row, positive otherwise; in the total with weight beta."""
    assert float(train.feature_scale(torch.ones(3, 8))) < 1e-9
    assert abs(float(train.feature_scale(torch.full((2, 8), 3.0))) - 4.0) < 1e-6
    m, objs = tiny
    m = copy.deepcopy(m).train()
    idx = list(range(4))
    torch.manual_seed(0)
    a = train.losses(m, objs[0], idx, 1.0, beta=0.0)
    torch.manual_seed(0)
    b = train.losses(m, objs[0], idx, 1.0, beta=2.0)
    assert float(a[4]) == 0.0 and float(b[4]) > 0
    assert torch.isclose(b[0], a[0] + b[4])


def test_shipped_trained_models():
    """Every trained weight file in models/ (not the random stand-in): its named
    config, at most 16 MiB, provenance of a finished run on the synthetic benchmark."""
    root = os.path.join(os.path.dirname(__file__), "..", "..", "models")
    files = [f for f in os.listdir(root) if f.endswith(".safetensors") and "random" not in f]
    for f in files:
        path = os.path.join(root, f)
        assert os.path.getsize(path) <= 16 * 2**20, f
        _, meta = safetensors_io.load(path)
        cfg = json.loads(meta["vtloc.config"])
        prov = json.loads(meta["vtloc.provenance"])
        assert cfg == config.named(prov["config"]) and prov["config"] in ("vtloc-lite", "vtloc-lite-xyz", "mcr-lite")
        assert prov["steps"] > 0 and prov["data_format"] == "vtloc-synth/1" and prov["data_seed"] == 1
        # The default benchmark's seen objects: 30 of its first 43, 48 of its 68 since the
        # everyday objects came (data/synth/objects.txt pins the first 43's split).
        seen = [o["name"] for o in prov["objects"] if o["object_split"] == "seen"]
        assert len(seen) in (30, 48), (f, len(seen))
        if len(seen) == 48:
            assert "spoon" in seen and "table_knife" not in seen, f
        model.load(path)  # loads into the reference
