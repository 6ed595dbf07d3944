"""Post-processing (SPEC 1, 3, 6) on hand-checked cases."""

import math

import pytest
import torch

from weights_tools import post


def test_normalisation():
    xyz = torch.tensor([[0., 0, 0], [4, 0, 0], [2, 3, 0], [2, -3, 0]])
    cloud = torch.cat([xyz, torch.tensor([[0., 0, 1]]).expand(4, 3)], dim=1)
    n, centre, scale = post.normalise_cloud(cloud)
    assert centre.tolist() == [2, 0, 0] and float(scale) == 3  # max(2, 2, 3, 3)
    assert torch.allclose(n[:, :3], torch.tensor([[-2 / 3, 0, 0], [2 / 3, 0, 0], [0, 1, 0], [0, -1, 0]]))
    assert torch.equal(n[:, 3:], cloud[:, 3:])  # normals unchanged


def test_top_k_ties_to_lower_index():
    cands = torch.tensor([[1., 0, 0], [0, 1, 0], [.5, 0, 0], [0, 0, 1], [0, -1, 0], [0, 0, .5]])
    idx, score = post.top_k(torch.zeros(3), cands, 4)
    assert idx.tolist() == [2, 5, 0, 1]
    assert score.tolist() == [0.25, 0.25, 1, 1]
    assert post.top_k(torch.zeros(3), cands, 10)[0].tolist() == [2, 5, 0, 1, 3, 4]


def test_heatmap_hand_case():
    centres = torch.tensor([[0., 0, 0], [1, 0, 0]])  # ranks 1, 2
    pts = torch.tensor([[0., 0, 0], [1, 0, 0], [.5, 0, 0], [3, 0, 0]])
    # p0: rank 1 at 0 -> 1; p1: rank 2 at 0 -> 1/2; p2: tie at .5 -> rank 1 -> e^-.5;
    # p3: rank 2 at 2 -> e^-2 / 2
    s = [1.0, 0.5, math.exp(-0.5), math.exp(-2) / 2]
    lo, hi = min(s), max(s)
    want = torch.tensor([(v - lo) / (hi - lo) for v in s])
    got = post.heatmap(pts, centres)
    assert got.dtype == torch.float32
    assert torch.allclose(got, want, atol=1e-7)
    assert got[0] == 1 and got[3] == 0


def test_heatmap_flat_is_zero():
    pts = torch.tensor([[1., 0, 0], [0, 1, 0], [0, 0, -1]])
    assert post.heatmap(pts, torch.zeros(1, 3)).tolist() == [0, 0, 0]


def test_rotation_copies():
    r = post.rotate_about_axis(torch.tensor([[2., 1, 0]]), [1., 1, 0], [0., 0, 2], math.pi / 2)
    assert torch.allclose(r, torch.tensor([[1., 2, 0]], dtype=torch.float64))
    pts, ranks = post.symmetric_copies(torch.tensor([[2., 1, 0]], dtype=torch.float64),
                                       torch.tensor([1]), [1., 1, 0], [0., 0, 1], 4)
    assert torch.allclose(pts, torch.tensor([[2., 1, 0], [1, 2, 0], [0, 1, 0], [1, 0, 0]],
                                            dtype=torch.float64), atol=1e-12)
    assert ranks.tolist() == [1, 1, 1, 1]
    # 120 degrees about (1, 1, 1) cycles the axes: x -> y -> z
    pts, _ = post.symmetric_copies(torch.tensor([[1., 0, 0]], dtype=torch.float64),
                                   torch.tensor([1]), [0., 0, 0], [1., 1, 1], 3)
    assert torch.allclose(pts, torch.eye(3, dtype=torch.float64), atol=1e-12)


def test_symmetry_prior_order_2_about_z():
    centres = torch.tensor([[.5, 0, .2], [0, .5, 0]])  # ranks 1, 2
    sym = ([0., 0, 0], [0., 0, 1], 2)  # copies: (-.5, 0, .2) rank 1, (0, -.5, 0) rank 2
    pts = torch.tensor([[.5, 0, .2], [-.5, 0, .2], [0, -.5, 0], [0, 0, .2]])
    # p0, p1 on rank-1 copies -> 1; p2 on a rank-2 copy -> 1/2;
    # p3: rank 1 at .5, rank 2 at sqrt(.29) -> e^-.5
    s = [1.0, 1.0, 0.5, math.exp(-0.5)]
    want = torch.tensor([(v - 0.5) / 0.5 for v in s])
    assert torch.allclose(post.heatmap(pts, centres, symmetry=sym), want, atol=1e-6)
    # without the prior p1 is nearest the rank-2 centre: e^-sqrt(.54) / 2
    assert post.heatmap(pts, centres)[1] < 0.5


def test_chamfer_hand_and_brute_force():
    a, b = torch.tensor([[0., 0, 0]]), torch.tensor([[1., 0, 0], [2, 0, 0]])
    assert float(post.chamfer(a, b)) == 1 + (1 + 4) / 2
    g = torch.Generator().manual_seed(0)
    a, b = torch.randn(7, 6, generator=g), torch.randn(5, 6, generator=g)
    al, bl = a.tolist(), b.tolist()

    def d2(p, q):
        return sum((x - y) ** 2 for x, y in zip(p, q))

    want = (sum(min(d2(p, q) for q in bl) for p in al) / len(al)
            + sum(min(d2(p, q) for p in al) for q in bl) / len(bl))
    assert abs(float(post.chamfer(a, b)) - want) < 1e-9
