"""FPS and ball query semantics (SPEC 2) on hand-made clouds with ties."""

import numpy as np
import pytest
import torch

from weights_tools.pointnet2 import ball_query, farthest_point_sample


def _d2(p, q):
    """float32 squared distance, summed (dx*dx + dy*dy) + dz*dz, one rounding per op."""
    dx, dy, dz = (np.float32(p[i]) - np.float32(q[i]) for i in range(3))
    return (dx * dx + dy * dy) + dz * dz


def brute_fps(pts, npoint):
    chosen, mind = [0], [np.float32(np.inf)] * len(pts)
    for _ in range(npoint - 1):
        for i, p in enumerate(pts):
            mind[i] = min(mind[i], _d2(p, pts[chosen[-1]]))
        best = max(mind)
        chosen.append(next(i for i, d in enumerate(mind) if d == best))
    return chosen


def brute_ball(pts, centre, r, nsample):
    r2 = np.float32(r) * np.float32(r)
    found = [i for i, p in enumerate(pts) if _d2(p, centre) <= r2][:nsample]
    return found + [found[0]] * (nsample - len(found))


def _t(pts):
    return torch.tensor(pts, dtype=torch.float32)[None]


def fps(pts, n):
    return farthest_point_sample(_t(pts), n)[0].tolist()


def ball(pts, centres, r, n):
    return ball_query(_t(pts), _t(centres), r, n)[0].tolist()


def test_fps_all_identical():
    pts = [[0.3, 0.3, 0.3]] * 5
    assert fps(pts, 3) == [0, 0, 0]  # every distance 0: the lowest index, 0, each time
    assert ball(pts, [pts[0]], 0.1, 4) == [[0, 1, 2, 3]]


def test_fps_line_with_tie():
    # d to x=0: 0 1 4 9 100 -> 4; then min d: 0 1 4 9 0 -> 3; then 0 1 1 0 0 -> tie -> 1;
    # then 0 0 1 0 0 -> 2; then all 0 -> 0
    pts = [[x, 0, 0] for x in (0, 1, 2, 3, 10)]
    assert fps(pts, 6) == [0, 4, 3, 1, 2, 0]


def test_fps_duplicates():
    pts = [[0, 0, 0], [2, 0, 0], [2, 0, 0], [0, 0, 0], [1, 0, 0]]
    # d: 0 4 4 0 1 -> tie 1/2 -> 1; then 0 0 0 0 1 -> 4; then all 0 -> 0
    assert fps(pts, 4) == [0, 1, 4, 0]


def test_fps_grid_square():
    pts = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]]
    # d: 0 1 1 2 .5 -> 3; min: 0 1 1 0 .5 -> tie 1/2 -> 1; 0 0 1 0 .5 -> 2; -> 4; -> 0
    assert fps(pts, 6) == [0, 3, 1, 2, 4, 0]


def test_ball_query_order_boundary_and_fill():
    pts = [[x, 0, 0] for x in (0, 0.5, 1.0, 0.25, 2.0)]
    # centre 1.0: d^2 = 1 .25 0 .5625 1 -> {1 (on the boundary r^2 = .25), 2}, fill with 1
    # centre 0.0: d^2 = 0 .25 1 .0625 4 -> {0, 1, 3}
    assert ball(pts, [[1.0, 0, 0], [0, 0, 0]], 0.5, 3) == [[1, 2, 1], [0, 1, 3]]
    assert ball(pts, [[0, 0, 0]], 0.5, 2) == [[0, 1]]              # truncated in index order
    assert ball(pts, [[0, 0, 0]], 0.5, 7) == [[0, 1, 3, 0, 0, 0, 0]]  # nsample > N
    # a centre that is a later point still takes earlier neighbours first
    assert ball(pts, [[0.25, 0, 0]], 0.3, 4) == [[0, 1, 3, 0]]


def _random_cloud(seed, n, quantum):
    g = torch.Generator().manual_seed(seed)
    pts = torch.randint(-4, 5, (n, 3), generator=g).float() * quantum  # many exact ties
    return pts.tolist()


@pytest.mark.parametrize("seed,n,quantum", [(0, 40, 0.25), (1, 60, 0.125), (2, 30, 0.1)])
def test_against_brute_force(seed, n, quantum):
    pts = _random_cloud(seed, n, quantum)
    idx = fps(pts, 16)
    assert idx == brute_fps(pts, 16)
    centres = [pts[i] for i in idx]
    for r, ns in ((0.3, 5), (0.55, 12), (1.0, 64)):
        got = ball(pts, centres, r, ns)
        assert got == [brute_ball(pts, c, r, ns) for c in centres]


def test_batch_rows_are_independent():
    a, b = _random_cloud(3, 32, 0.25), _random_cloud(4, 32, 0.25)
    both = farthest_point_sample(torch.tensor([a, b]), 8)
    assert both[0].tolist() == fps(a, 8) and both[1].tolist() == fps(b, 8)
