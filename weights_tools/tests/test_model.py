"""The tiny configs end to end (in memory), the ILU iteration count, config checks."""

import copy

import pytest
import torch

from weights_tools import config, post, synthetic
from weights_tools.export import random_model
from weights_tools.model import VTLoc
from weights_tools.tactile import preprocess


@pytest.fixture(scope="module")
def tiny():
    return random_model(config.named("vtloc-tiny"), seed=0)


def _inputs(cfg, seed=5):
    t = cfg["tactile"]
    img = preprocess(synthetic.tactile_image(seed), t["crop"], t["in_size"])
    cloud, _, _ = post.normalise_cloud(
        torch.from_numpy(synthetic.superellipsoid_cloud(seed, cfg["point"]["n_points"])))
    if not cfg["point"]["use_normals"]:
        cloud = cloud[:, :3]
    return img, cloud[None]


def test_tiny_runs_with_o1_activations(tiny):
    cfg = tiny.cfg
    with torch.no_grad():
        out = tiny(*_inputs(cfg))
    assert out["tactile.feature"].shape == (1, cfg["C"])
    assert out["point.feature"].shape == (1, cfg["C"])
    assert out["gma.cloud"].shape == (1, 32, 6)
    assert out["ilu.c"].shape == (1, 4, 3) and torch.equal(out["contact"], out["ilu.c"][:, -1])
    for k in ("tactile.feature", "point.feature", "gma.cloud", "ilu.c"):
        assert 0.05 < float(out[k].std()) < 20, k
    assert torch.all(torch.isfinite(out["contact"]))
    n = torch.linalg.vector_norm(out["gma.cloud"][0, :, 3:], dim=-1)
    assert torch.allclose(n, torch.ones_like(n), atol=1e-5)


def test_ilu_iterations(tiny):
    ft, fp = torch.randn(2, 16), torch.randn(2, 16)
    with torch.no_grad():
        c0 = tiny.ilu(ft, fp, 0)
        cp, _ = tiny.contact(ft, fp, 0)
        c4, c9 = tiny.ilu(ft, fp, 4), tiny.ilu(ft, fp, 9)
    assert c0.shape == (2, 0, 3) and torch.equal(cp, torch.zeros(2, 3))  # N = 0: c = 0
    assert torch.equal(c9[:, :4], c4)  # every c_k is returned, a prefix of longer runs
    with pytest.raises(ValueError):
        tiny.ilu(ft, fp, 65)


def test_ilu_recurrence_by_hand(tiny):
    ilu = tiny.ilu
    ft, fp = torch.randn(1, 16), torch.randn(1, 16)
    h, x, c = torch.tanh(ft), torch.cat([fp, torch.relu(ft)], -1), torch.zeros(1, 3)
    want = []
    with torch.no_grad():
        for _ in range(3):
            z = torch.sigmoid(ilu.convz(torch.cat([h, x], -1)))
            r = torch.sigmoid(ilu.convr(torch.cat([h, x], -1)))
            q = torch.tanh(ilu.convq(torch.cat([r * h, x], -1)))
            h = (1 - z) * h + z * q
            c = c + ilu.head[2](torch.relu(ilu.head[0](h)))
            want.append(c)
        assert torch.allclose(ilu(ft, fp, 3), torch.stack(want, 1), atol=1e-6)


def test_mcr_tiny_runs():
    m = random_model(config.named("vtloc-mcr-tiny"), seed=1)
    with torch.no_grad():
        out = m(*_inputs(m.cfg))
    assert set(out) >= {"point.sa1.ball.1", "point.sa2.ball.1", "contact"}
    assert "ilu.c" not in out and "gma.cloud" not in out
    assert out["point.sa1.ball.1"].shape == (1, 32, 16)
    assert float(out["contact"].abs().max()) <= 1


def test_batch_matches_single(tiny):
    a, b = _inputs(tiny.cfg, 5), _inputs(tiny.cfg, 6)
    with torch.no_grad():
        both = tiny(torch.cat([a[0], b[0]]), torch.cat([a[1], b[1]]))
        one = tiny(*b)
    assert torch.allclose(both["contact"][1], one["contact"][0], atol=1e-5)
    assert torch.equal(both["point.sa1.fps"][1], one["point.sa1.fps"][0])


def test_config_validation():
    cfg = config.named("vtloc-tiny")
    assert config.from_json(config.to_json(cfg)) == cfg
    for bad in ({"head": "mlp"}, {"ilu": None}, {"K": 0}, {"extra": 1}):
        c = copy.deepcopy(cfg)
        c.update(bad)
        with pytest.raises(ValueError):
            config.canonical(c)
    c = copy.deepcopy(cfg)
    c["point"]["sa"][0]["nsample"] = [8, 8]  # one entry per scale
    with pytest.raises(ValueError):
        VTLoc(c)
