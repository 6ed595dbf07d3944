"""golden: every SPEC 8 name with the right shape and dtype, consistent values,
and the same result from files as from the synthetic generators."""

import json
import os

import numpy as np
import pytest
import torch
from PIL import Image

from test_pointnet_ops import brute_fps
from weights_tools import config, export, golden, model, post, safetensors_io, synthetic
from weights_tools.ply import read_ply, write_ply
from weights_tools.tactile import preprocess

F32, I32, U8 = torch.float32, torch.int32, torch.uint8


def expected(cfg, iters, k, n, m):
    C, S = cfg["C"], cfg["tactile"]["in_size"]
    want = {
        "input.tactile": (U8, (120, 160, 3)), "input.cloud": (F32, (n, 6)),
        "input.candidates": (F32, (m, 3)),
        "tactile.input": (F32, (1, 3, S, S)), "tactile.feature": (F32, (C,)),
        "point.cloud": (F32, (n, 6 if cfg["point"]["use_normals"] else 3)),
        "point.centre": (F32, (3,)), "point.scale": (F32, ()),
        "point.feature": (F32, (C,)), "contact": (F32, (3,)), "contact.object": (F32, (3,)),
        "topk.index": (I32, (k,)), "topk.score": (F32, (k,)), "heatmap": (F32, (n,)),
    }
    for i, sa in enumerate(cfg["point"]["sa"]):
        want[f"point.sa{i + 1}.fps"] = (I32, (sa["npoint"],))
        for s, ns in enumerate(sa["nsample"]):
            want[f"point.sa{i + 1}.ball.{s}"] = (I32, (sa["npoint"], ns))
    if cfg["gma"]:
        want["gma.cloud"] = (F32, (cfg["gma"]["n_points"], 6))
        want["gma.chamfer"] = (F32, ())
    if cfg["head"] == "ilu":
        want["ilu.c"] = (F32, (iters, 3))
    return want


@pytest.fixture(scope="module")
def weights(tmp_path_factory):
    d = tmp_path_factory.mktemp("w")
    paths = {}
    for name in ("vtloc-tiny", "vtloc-mcr-tiny"):
        paths[name] = str(d / f"{name}.safetensors")
        model.save(export.random_model(config.named(name), 0), paths[name])
    return paths


def _golden(weights, out, *extra):
    assert golden.main(["--weights", weights, "-o", str(out), *extra]) == 0
    return safetensors_io.load(out)


@pytest.mark.parametrize("name", ["vtloc-tiny", "vtloc-mcr-tiny"])
def test_names_shapes_dtypes(weights, tmp_path, name):
    t, meta = _golden(weights[name], tmp_path / "g.safetensors",
                      "--synthetic-tactile", "3", "--synthetic-cloud", "4")
    cfg = json.loads(meta["vtloc.config"])
    assert cfg == config.named(name) and meta["format"] == "pt"
    want = expected(cfg, 4, 5, 128, 128)
    assert {k: (v.dtype, tuple(v.shape)) for k, v in t.items()} == want


def test_values_are_consistent(weights, tmp_path):
    t, meta = _golden(weights["vtloc-tiny"], tmp_path / "g.safetensors",
                      "--synthetic-tactile", "3", "--synthetic-cloud", "4")
    cfg = config.named("vtloc-tiny")
    assert torch.equal(t["input.tactile"], torch.from_numpy(synthetic.tactile_image(3)))
    assert torch.equal(t["input.cloud"], torch.from_numpy(synthetic.superellipsoid_cloud(4, 128)))
    x = preprocess(t["input.tactile"], cfg["tactile"]["crop"], cfg["tactile"]["in_size"])
    assert torch.allclose(x, t["tactile.input"], atol=1e-6)
    cloud = t["point.cloud"]
    assert torch.allclose(cloud[:, :3] * t["point.scale"] + t["point.centre"],
                          t["input.cloud"][:, :3], atol=1e-4)
    assert abs(float(torch.linalg.vector_norm(cloud[:, :3], dim=1).max()) - 1) < 1e-6
    assert t["point.sa1.fps"].tolist() == brute_fps(cloud[:, :3].tolist(), 32)
    # the ball of each centroid starts at or before the centroid and contains it
    for i, f in enumerate(t["point.sa1.fps"].tolist()):
        assert f in t["point.sa1.ball.0"][i].tolist()
    assert torch.equal(t["contact"], t["ilu.c"][-1])
    idx, score = post.top_k(t["contact"], t["point.cloud"][:, :3], 5)
    assert torch.equal(t["topk.index"], idx.int()) and torch.equal(t["topk.score"], score)
    assert torch.equal(t["heatmap"], post.heatmap(cloud[:, :3], cloud[idx.long(), :3]))
    assert float(t["heatmap"].max()) == 1 and float(t["heatmap"].min()) == 0
    assert abs(float(t["gma.chamfer"]) - float(post.chamfer(t["gma.cloud"], cloud))) < 1e-5
    # a float32 run of the network agrees with the float64 golden
    m = model.load(weights["vtloc-tiny"])
    with torch.no_grad():
        out = m(t["tactile.input"], cloud[None])
    for k in ("tactile.feature", "point.feature", "contact"):
        assert torch.allclose(out[k][0], t[k], atol=1e-4), k
    assert meta["vtloc.golden.iters"] == "4" and meta["vtloc.golden.tactile"] == "synthetic:3"


def test_file_inputs_match_synthetic(weights, tmp_path):
    Image.fromarray(synthetic.tactile_image(3)).save(tmp_path / "t.png")
    cloud = synthetic.superellipsoid_cloud(4, 128)
    write_ply(tmp_path / "c.ply", cloud)
    assert np.array_equal(read_ply(tmp_path / "c.ply"), cloud)
    np.savetxt(tmp_path / "cand.txt", cloud[:, :3].astype(np.float64), fmt="%.9g")
    a, _ = _golden(weights["vtloc-tiny"], tmp_path / "a.safetensors",
                   "--synthetic-tactile", "3", "--synthetic-cloud", "4")
    b, meta = _golden(weights["vtloc-tiny"], tmp_path / "b.safetensors",
                      "--tactile", str(tmp_path / "t.png"), "--cloud", str(tmp_path / "c.ply"),
                      "--candidates", str(tmp_path / "cand.txt"))
    assert set(a) == set(b) and all(torch.equal(a[k], b[k]) for k in a)
    assert meta["vtloc.golden.cloud"].startswith("file:")


def test_iters_k_and_symmetry_options(weights, tmp_path):
    t, _ = _golden(weights["vtloc-tiny"], tmp_path / "g.safetensors", "--synthetic-tactile", "3",
                   "--synthetic-cloud", "4", "--iters", "0", "--K", "2")
    assert t["ilu.c"].shape == (0, 3) and torch.equal(t["contact"], torch.zeros(3))
    assert t["topk.index"].shape == (2,)
    # order-2 symmetry about the vertical axis through the cloud's centre
    c = [float(v) for v in t["point.centre"]]
    s, _ = _golden(weights["vtloc-tiny"], tmp_path / "s.safetensors", "--synthetic-tactile", "3",
                   "--synthetic-cloud", "4", "--symmetry", f"{c[0]},{c[1]},{c[2]},0,0,1,2")
    base, _ = _golden(weights["vtloc-tiny"], tmp_path / "b.safetensors", "--synthetic-tactile",
                      "3", "--synthetic-cloud", "4")
    assert not torch.equal(s["heatmap"], base["heatmap"])
    assert torch.equal(s["topk.index"], base["topk.index"])
    # a point and its half-turn image score the same when both have a twin in the cloud
    cand = s["point.cloud"][s["topk.index"].long(), :3]
    twins = cand * torch.tensor([-1.0, -1.0, 1.0])
    want = post.heatmap(s["point.cloud"][:, :3], torch.cat([cand, twins]),
                        ranks=list(range(1, 6)) * 2)
    assert torch.allclose(s["heatmap"], want, atol=1e-6)


def test_missing_inputs_are_errors(weights, tmp_path):
    assert golden.main(["--weights", weights["vtloc-tiny"], "--synthetic-tactile", "1",
                        "-o", str(tmp_path / "x")]) == 2
    assert not os.path.exists(tmp_path / "x")
