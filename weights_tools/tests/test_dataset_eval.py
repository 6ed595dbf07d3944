"""dataset reader, metrics (hand cases) and eval.py end to end on a tiny fake dataset."""

import csv
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
import torch

from fake_dataset import make_dataset
from weights_tools import eval as eval_mod
from weights_tools import metrics, post
from weights_tools.dataset import DatasetError, TOUCH_COLUMNS, read_dataset

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    return make_dataset(str(tmp_path_factory.mktemp("ds") / "data"))


@pytest.fixture(scope="module")
def tiny_weights(tmp_path_factory):
    path = tmp_path_factory.mktemp("w") / "tiny.safetensors"
    subprocess.run([sys.executable, "-m", "weights_tools.export", "--config", "vtloc-tiny",
                    "--seed", "0", "-o", str(path)], cwd=ROOT, check=True, capture_output=True)
    return str(path)


def _copy(data_dir, tmp_path):
    dst = str(tmp_path / "copy")
    shutil.copytree(data_dir, dst)
    return dst


# ---------------------------------------------------------------- dataset

def test_reader_round_trip(data_dir):
    ds = read_dataset(data_dir)
    assert ds.seed == 0 and ds.sensor["height"] == 120 and len(ds.objects) == 3
    assert [o.object_split for o in ds.objects] == ["seen", "seen", "unseen"]
    o = ds.objects[0]
    assert o.points.shape == (128, 6) and o.points.dtype == np.float64
    with open(os.path.join(o.folder, "points.csv")) as f:
        first = next(csv.DictReader(f))
    assert o.points[0, 0] == float(first["x"]) and o.points[0, 5] == float(first["nz"])
    assert [t.id for t in o.touches] == list(range(12))
    test = [t for t in o.touches if t.split == "test"]
    assert o.candidate_ids == [t.id for t in test]
    assert np.array_equal(o.candidates, np.stack([t.contact for t in test]))
    assert sorted(t.order for t in o.touches if t.split != "extra") == list(range(10))
    assert all(t.order == -1 and not t.motion.any() for t in o.touches if t.split == "extra")
    img = o.image(o.touches[3])
    assert img.shape == (120, 160, 3) and img.dtype == np.uint8
    assert o.touches[0].R.shape == (3, 3) and abs(np.linalg.det(o.touches[0].R) - 1) < 1e-9


def test_reader_errors(data_dir, tmp_path):
    with pytest.raises(DatasetError, match="dataset.json: missing"):
        read_dataset(str(tmp_path))
    d = _copy(data_dir, tmp_path)
    obj = os.path.join(d, "objects", "shape01")
    # a touches.csv without a column
    path = os.path.join(obj, "touches.csv")
    with open(path) as f:
        rows = list(csv.reader(f))
    keep = [i for i, c in enumerate(rows[0]) if c != "dz"]
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows([[r[i] for i in keep] for r in rows])
    with pytest.raises(DatasetError, match=r"shape01/touches.csv: missing columns dz"):
        read_dataset(d)
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)
    os.remove(os.path.join(obj, "touches", "0003.png"))
    with pytest.raises(DatasetError, match=r"touches.csv:5: image touches/0003.png does not exist"):
        read_dataset(d)
    os.remove(os.path.join(obj, "points.csv"))
    with pytest.raises(DatasetError, match=r"shape01/points.csv: missing"):
        read_dataset(d)
    with open(os.path.join(d, "dataset.json")) as f:
        meta = json.load(f)
    meta["format"] = "something/2"
    with open(os.path.join(d, "dataset.json"), "w") as f:
        json.dump(meta, f)
    with pytest.raises(DatasetError, match="format 'something/2'"):
        read_dataset(d)


def test_reader_bad_number(data_dir, tmp_path):
    d = _copy(data_dir, tmp_path)
    path = os.path.join(d, "objects", "shape00", "touches.csv")
    with open(path) as f:
        rows = list(csv.reader(f))
    rows[2][TOUCH_COLUMNS.index("cy")] = "abc"
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)
    with pytest.raises(DatasetError, match=r"touches.csv:3: column cy: 'abc' is not a number"):
        read_dataset(d)


# ---------------------------------------------------------------- metrics

def _frame():
    # a cloud whose diameter is exactly 20 (two points at x = +-10) and three candidates
    rng = np.random.default_rng(0)
    p = rng.uniform(-3, 3, size=(50, 3))
    p[0], p[1] = [-10, 0, 0], [10, 0, 0]
    cands = np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0], [0, 0, -3.0], [2, 2, 2.0]])
    return metrics.ObjectFrame(np.concatenate([p, np.zeros_like(p)], 1), cands)


def test_metrics_perfect_prediction():
    f = _frame()
    for j in range(f.cand.shape[0]):
        gt = f.cand[j].numpy()
        m = metrics.touch_metrics(f, gt, gt, topk=1)
        # MPE 0 up to post.heatmap's float32 result (with K > 1 the other ranks add heat)
        assert m["error_mm"] == 0 and m["nd"] == 0 and m["rank"] == 1 and m["mpe"] < 1e-7
    rows = metrics.aggregate([{"object": "a", **metrics.touch_metrics(f, f.cand[0], f.cand[0], 1)}],
                             {"a": "uniform"}, "m")
    assert rows[1] == {"method": "m", "subset": "uniform", "objects": 1, "touches": 1, "mm": 0.0,
                       "nd": 0.0, "top1": 100.0, "top5": 100.0, "mpe": pytest.approx(0, abs=1e-7)}
    assert rows[0]["objects"] == 0 and rows[0]["mm"] is None


def test_metrics_known_offset():
    f = _frame()
    assert f.D == pytest.approx(20.0)
    gt = np.array([1.0, 0, 0])
    m = metrics.touch_metrics(f, gt + [0, 0, 1.5], gt)
    assert m["error_mm"] == pytest.approx(1.5) and m["nd"] == pytest.approx(7.5)
    assert m["rank"] == 1  # (1, 0, 1.5) is nearest to candidate 0 (d^2 = 2.25)
    m = metrics.touch_metrics(f, [-0.9, 0, 0], gt)  # nearer to candidate 1
    assert m["rank"] == 2 and m["error_mm"] == pytest.approx(1.9)
    assert 0 < m["mpe"] < 1


def test_rank_ties_go_to_lower_index():
    f = _frame()
    # (0, 0, 0) is equally far (1) from candidates 0 and 1
    assert metrics.touch_metrics(f, [0, 0, 0], [1.0, 0, 0])["rank"] == 1
    assert metrics.touch_metrics(f, [0, 0, 0], [-1.0, 0, 0])["rank"] == 2
    # the ground-truth candidate is the nearest to c^gt, lower index on a tie
    assert metrics.gt_candidate(f.normalise([0, 0, 0]), f.cand_n) == 0
    order = metrics.rank_order(f.normalise([0, 0, 0]), f.cand_n).tolist()
    assert order[:2] == [0, 1] and order[2] == 2 and order[3:5] == [3, 4]


def test_mpe_uses_spec3_heatmap():
    f = _frame()
    pred, gt = np.array([0.5, 0.5, 0.0]), f.cand[2].numpy()
    order = metrics.rank_order(f.normalise(pred), f.cand_n)
    heat = post.heatmap(f.xyz_n, f.cand_n[order[:2]])
    g = torch.exp(-torch.linalg.vector_norm(f.xyz_n - f.normalise(gt), dim=1))
    g = (g - g.min()) / (g.max() - g.min())
    want = float((heat.double() - g).abs().mean())
    assert metrics.touch_metrics(f, pred, gt, topk=2)["mpe"] == pytest.approx(want, abs=1e-6)
    # K is capped at the number of candidates
    assert metrics.touch_metrics(f, pred, gt, topk=50)["mpe"] == pytest.approx(
        metrics.touch_metrics(f, pred, gt, topk=6)["mpe"])


def test_aggregation_per_object_first():
    per_touch = ([{"object": "a", "error_mm": 1.0, "nd": 1.0, "rank": 1, "mpe": 0.1}] * 3
                 + [{"object": "b", "error_mm": 5.0, "nd": 3.0, "rank": 7, "mpe": 0.3}])
    rows = {r["subset"]: r for r in metrics.aggregate(per_touch, {"a": "uniform", "b": "non-uniform"}, "x")}
    assert rows["all"]["mm"] == 3.0 and rows["all"]["top1"] == 50.0 and rows["all"]["touches"] == 4
    assert rows["uniform"]["mm"] == 1.0 and rows["non-uniform"]["top5"] == 0.0


# ---------------------------------------------------------------- eval.py

def test_eval_end_to_end(data_dir, tiny_weights, tmp_path):
    out = tmp_path / "r.json"
    r = subprocess.run([sys.executable, "-m", "weights_tools.eval", "--model", tiny_weights,
                        "--data", data_dir, "--json", str(out)], cwd=ROOT, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    assert "uniform" in r.stdout and "Top-1" in r.stdout
    rep = json.loads(out.read_text())
    assert set(rep) == {"format", "model", "config", "data", "split", "objects", "iters", "topk",
                        "sequence", "mm_per_px", "rows", "per_touch", "time_per_touch_ms"}
    assert rep["mm_per_px"] is None  # the tiny model records no sensor
    assert rep["format"] == "vtloc-eval/1" and rep["config"] == "vtloc-tiny" and rep["iters"] == 4
    assert [r["subset"] for r in rep["rows"]] == ["non-uniform", "uniform", "all"]
    assert all(set(r) == {"method", "subset", "objects", "touches", "mm", "nd", "top1", "top5", "mpe"}
               and r["method"] == "vtloc-tiny" for r in rep["rows"])
    assert rep["rows"][2]["touches"] == 12 and rep["rows"][2]["objects"] == 3
    pt = rep["per_touch"]
    assert len(pt) == 12 and set(pt[0]) == {"object", "touch", "subset", "error_mm", "nd", "rank",
                                           "mpe", "contact"}
    # per-touch numbers agree with the metrics recomputed from the reported contact
    ds = read_dataset(data_dir)
    o = ds.object(pt[0]["object"])
    t = [t for t in o.touches if t.id == pt[0]["touch"]][0]
    m = metrics.touch_metrics(metrics.ObjectFrame(o.points, o.candidates), pt[0]["contact"], t.contact)
    assert m["error_mm"] == pytest.approx(pt[0]["error_mm"]) and m["rank"] == pt[0]["rank"]
    # the model really ran: the contact matches a direct prediction
    from weights_tools import model as model_mod
    direct = eval_mod.predict(model_mod.load(tiny_weights), o, [t])[0]
    assert np.allclose(direct, pt[0]["contact"], atol=1e-5)


def test_eval_filters(data_dir, tiny_weights):
    from weights_tools import model as model_mod
    m = model_mod.load(tiny_weights)
    ds = read_dataset(data_dir)
    rows, per_touch, _, _ = eval_mod.evaluate(m, ds, split="train", objects="unknown")
    assert {p["object"] for p in per_touch} == {"shape02"} and len(per_touch) == 6


def test_eval_cli_errors(tiny_weights, tmp_path, capsys):
    assert eval_mod.main(["--model", tiny_weights, "--data", str(tmp_path)]) == 2
    assert "dataset.json: missing" in capsys.readouterr().err
