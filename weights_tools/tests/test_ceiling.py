"""The single-touch bound (weights_tools.ceiling): its pieces do what the
results in docs/results.md rely on."""

import math

import numpy as np
import torch

from weights_tools import ceiling


def test_geometric_median_is_the_least_summed_distance():
    # Three points on a line: the middle one, not the mean.
    p = np.array([[0.0, 0, 0], [1, 0, 0], [10, 0, 0]])
    assert np.allclose(ceiling.geometric_median(p), [1, 0, 0], atol=1e-4)
    # A symmetric set: its centre.
    sq = np.array([[1.0, 1, 0], [-1, 1, 0], [1, -1, 0], [-1, -1, 0]])
    assert np.allclose(ceiling.geometric_median(sq), 0, atol=1e-6)


def stripes(freq, angle, h=30, w=40):
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    u = (xs - w / 2) * math.cos(angle) + (ys - h / 2) * math.sin(angle)
    return torch.from_numpy(np.sin(2 * math.pi * freq * u).astype(np.float32))


def test_rotation_search_finds_a_spun_copy():
    # Stripes of five frequencies, all horizontal; the query is the third one
    # turned by 90 degrees, which matches nothing unless rotations are searched.
    freqs = [0.05, 0.08, 0.11, 0.14, 0.17]
    db_maps = torch.stack([stripes(f, 0.0) for f in freqs])
    mask = ceiling.disc(30, 40)
    db = ceiling.descriptors(db_maps, mask, plane=False)
    contacts = np.array([[float(i), 0, 0] for i in range(5)])
    query = stripes(freqs[2], math.pi / 2)
    unrotated = ceiling.descriptors(query[None], mask, plane=False) @ db.t()
    assert float(unrotated.abs().max()) < 0.5
    pred = ceiling.knn_predictions(db, contacts, [query], [1], mask, plane=False)
    assert np.allclose(pred[0, 0], contacts[2])
    best = (ceiling.descriptors(ceiling.rotated(query[None]), mask, False) @ db.t()).max()
    assert float(best) > 0.95


def test_plane_removal_ignores_tilt_and_press():
    # The same bump seen with a tilt (a ramp) and a deeper press (a gain and an
    # offset) has the same descriptor once the plane is removed.
    ys, xs = np.mgrid[0:30, 0:40].astype(np.float32)
    bump = np.exp(-((xs - 24) ** 2 + (ys - 12) ** 2) / 20)
    other = np.exp(-((xs - 14) ** 2 + (ys - 18) ** 2) / 20)
    mask = ceiling.disc(30, 40)
    maps = torch.from_numpy(np.stack([bump, 2 * bump + 0.3 + 0.05 * xs - 0.02 * ys, other]).astype(np.float32))
    d = ceiling.descriptors(maps, mask, plane=True)
    assert float(d[0] @ d[1]) > 0.999
    assert float(d[0] @ d[2]) < 0.5
    # Without plane removal the ramp spoils the match.
    d0 = ceiling.descriptors(maps, mask, plane=False)
    assert float(d0[0] @ d0[1]) < 0.9
