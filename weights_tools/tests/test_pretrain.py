"""pretrain.py: places grouped as --extra-views writes them, the loss, a run that never
reads validation or test touches, resume, and train.py starting from its encoder."""

import csv
import glob
import os
import shutil
import types

import numpy as np
import pytest
import torch

from fake_dataset import make_dataset
from weights_tools import config, pretrain, train
from weights_tools.dataset import read_dataset


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    root = make_dataset(str(tmp_path_factory.mktemp("ds") / "data"), n_train=10, n_extra=8)
    # as --extra-views 2 writes them: each pair of consecutive extra rows at one contact
    for folder in glob.glob(os.path.join(root, "objects", "*")):
        with open(os.path.join(folder, "touches.csv"), newline="") as f:
            rows = list(csv.DictReader(f))
        extra = [r for r in rows if r["split"] == "extra"]
        for first, second in zip(extra[0::2], extra[1::2]):
            for k in ("cx", "cy", "cz"):
                second[k] = first[k]
        with open(os.path.join(folder, "touches.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    return root


@pytest.fixture(autouse=True)
def hold_half(monkeypatch):
    monkeypatch.setattr(pretrain, "HELD_SHARE", 0.5)  # a tiny dataset needs more held-out places


def _touch(i, c):
    return types.SimpleNamespace(id=i, contact=np.array(c, dtype=np.float64))


def test_places_group_consecutive_renders_of_one_contact():
    ts = [_touch(0, [1, 2, 3]), _touch(1, [1, 2, 3.0000004]), _touch(2, [1, 2, 3.0000001]),
          _touch(3, [1, 2, 3.01]), _touch(4, [1, 2, 3])]  # 4 is at 0's place, but not next to it
    assert pretrain.places(ts) == [[0, 1, 2], [3], [4]]


def test_nt_xent_prefers_the_pair():
    z = torch.nn.functional.normalize(torch.randn(6, 8, generator=torch.Generator().manual_seed(0)), dim=-1)
    same = pretrain.nt_xent(z, z, 0.1)
    shuffled = pretrain.nt_xent(z, z[[1, 2, 3, 4, 5, 0]], 0.1)
    assert same < shuffled
    # orthogonal, well separated pairs: the loss is near 0; a uniform guess is log(2P - 1)
    e = torch.eye(6)
    assert pretrain.nt_xent(e, e, 0.05) < 1e-6
    assert torch.isclose(pretrain.nt_xent(torch.ones(6, 8) / 8 ** 0.5, torch.ones(6, 8) / 8 ** 0.5, 1.0),
                         torch.log(torch.tensor(11.0)))


def _args(data_dir, out, *extra):
    return pretrain.parse_args(["--config", "vtloc-tiny", "--data", data_dir, "--out", str(out), "--threads", "1",
                                "--places", "3", "--val-fraction", "0.3", *extra])


def test_frames_are_the_training_touches_only(data_dir):
    ds = read_dataset(data_dir)
    f = pretrain.Frames(ds, 0.3)
    m = train.make_model(config.named("vtloc-tiny"), 0)
    objs = train.load_objects(m, ds, 0.3)
    assert sum(len(p) for p in f.train + f.held) == f.images.shape[0] == sum(o.n_train for o in objs)
    want = {(o.name, i) for o in ds.objects if o.object_split == "seen" for i in train.split_contacts(o, 0.3)[0]}
    assert len(want) == f.images.shape[0]
    # the multi-render places: some held out (two renders each), some trained on
    assert f.held and all(len(p) == 2 for p in f.held)
    assert any(len(p) == 2 for p in f.train)


def test_run_resume_and_init(data_dir, tmp_path):
    full, step = pretrain.run(_args(data_dir, tmp_path / "a", "--steps", "6"))
    assert step == 6 and (tmp_path / "a" / "tactile.pt").exists()
    with open(tmp_path / "a" / "log.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows[0]["step"] == "0" and rows[-1]["step"] == "6" and np.isfinite(float(rows[-1]["loss"]))
    assert 0 <= float(rows[-1]["retrieval"]) <= 1 and float(rows[-1]["retrieval_chance"]) > 0
    # interrupted and resumed: the same encoder as the run straight through
    pretrain.run(_args(data_dir, tmp_path / "b", "--steps", "6", "--stop-after", "3"))
    assert not (tmp_path / "b" / "tactile.pt").exists()
    with pytest.raises(ValueError, match="--resume"):
        pretrain.run(_args(data_dir, tmp_path / "b", "--steps", "6"))
    with open(tmp_path / "b" / "log.csv", "a") as f:
        f.write("5,1.0,9.9,,\n")  # written after the checkpoint by a run that was then killed
    resumed, step = pretrain.run(_args(data_dir, tmp_path / "b", "--steps", "6", "--resume", "--places", "2"))
    sa, sb = full.state_dict(), resumed.state_dict()
    assert step == 6 and all(torch.equal(sa[k], sb[k]) for k in sa)  # --places from the checkpoint
    with open(tmp_path / "b" / "log.csv") as f:
        assert [r["step"] for r in csv.DictReader(f)] == ["0", "6"]
    other = make_dataset(str(tmp_path / "other_b"), n_train=10, n_extra=8, seed=2)
    with pytest.raises(ValueError, match="pretrained on other training touches"):
        pretrain.run(_args(other, tmp_path / "b", "--steps", "8", "--resume"))
    # train.py starts its tactile encoder there (and nothing else), and its checkpoint says so
    (tmp_path / "t").mkdir()
    t = train.Trainer(train.parse_args(["--config", "vtloc-tiny", "--data", data_dir, "--out", str(tmp_path / "t"),
                                        "--batch", "4", "--threads", "1", "--steps", "1", "--val-fraction", "0.3",
                                        "--init-tactile", str(tmp_path / "a" / "tactile.pt")]),
                      str(tmp_path / "t" / "checkpoint.pt"), None)
    got = t.model.tactile.state_dict()
    assert all(torch.equal(got[k], sa[k]) for k in sa)
    scratch = train.make_model(config.named("vtloc-tiny"), 0).point.state_dict()
    assert all(torch.equal(t.model.point.state_dict()[k], scratch[k]) for k in scratch)
    t.checkpoint()
    assert torch.load(tmp_path / "t" / "checkpoint.pt")["args"]["init_tactile"].endswith("tactile.pt")
    # another config, other training touches or another validation split: an error, not silent
    # leakage; the same touches in another folder are the same data
    tac = str(tmp_path / "a" / "tactile.pt")
    other = make_dataset(str(tmp_path / "other"), n_train=10, n_extra=8, seed=1)
    moved = shutil.copytree(data_dir, str(tmp_path / "moved"))
    for extra, msg in ((["--config", "vtloc-lite"], "config vtloc-tiny .*, this run has vtloc-lite"),
                       (["--val-fraction", "0.1"], "val_fraction 0.3 .*, this run has 0.1"),
                       (["--data", other], "pretrained with touches"),
                       (["--data", moved], None)):
        a = train.parse_args(["--config", "vtloc-tiny", "--data", data_dir, "--out", str(tmp_path / "u"),
                              "--val-fraction", "0.3", "--steps", "1"] + extra)
        fp = train.training_fingerprint(read_dataset(a.data), a.val_fraction)
        if msg is None:
            train.init_tactile(train.make_model(config.named(a.config), 0), tac, a, fp)
            continue
        with pytest.raises(ValueError, match=msg):
            train.init_tactile(train.make_model(config.named(a.config), 0), tac, a, fp)
    # a file that is not one: one line through main, exit status 2
    (tmp_path / "bad.pt").write_bytes(b"not a torch file")
    assert train.main(["--config", "vtloc-tiny", "--data", data_dir, "--out", str(tmp_path / "v"), "--steps", "1",
                       "--threads", "1", "--init-tactile", str(tmp_path / "bad.pt")]) == 2
    (tmp_path / "b" / "checkpoint.pt").write_bytes(b"truncated")
    assert pretrain.main(["--config", "vtloc-tiny", "--data", data_dir, "--out", str(tmp_path / "b"), "--steps", "8",
                          "--resume"]) == 2


def test_frozen_tactile_stays_as_pretrained(data_dir, tmp_path):
    pretrain.run(_args(data_dir, tmp_path / "p", "--steps", "2"))
    tac = str(tmp_path / "p" / "tactile.pt")
    want = torch.load(tac)["tactile"]
    m, _, _ = train.run(train.parse_args(["--config", "vtloc-tiny", "--data", data_dir, "--out", str(tmp_path / "t"),
                                          "--batch", "4", "--threads", "1", "--steps", "4", "--ckpt-minutes", "0",
                                          "--val-fraction", "0.3",
                                          "--init-tactile", tac, "--freeze-tactile"]))
    got = m.tactile.state_dict()  # weights and BatchNorm statistics, through validations too
    assert all(torch.equal(got[k], want[k]) for k in want)
    scratch = train.make_model(config.named("vtloc-tiny"), 0).point.state_dict()
    assert any(not torch.equal(m.point.state_dict()[k], scratch[k]) for k in scratch if k.endswith("weight"))
    assert torch.load(tmp_path / "t" / "checkpoint.pt")["args"]["freeze_tactile"] is True
