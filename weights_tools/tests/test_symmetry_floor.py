"""models/symmetry_floor.py: the raw-ND floor a symmetric object sets any estimator."""

import importlib.util
import os
import struct

import numpy as np
import pytest

_PATH = os.path.join(os.path.dirname(__file__), "..", "..", "models", "symmetry_floor.py")
_spec = importlib.util.spec_from_file_location("symmetry_floor", _PATH)
sf = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sf)


def test_two_fold_floor_is_half_the_copies_distance():
    # Orbit {(r, 0, 5), (-r, 0, 5)}: any point between the two is 2r in all from them.
    sym = {"axis": [0, 0, 1], "order": 2, "point": [0, 0, 0]}
    floor, surface, copy = sf.window_floor(sym, [7.0, 0.0, 5.0])
    assert floor == pytest.approx(7.0, abs=1e-6)
    assert surface is None
    assert copy == pytest.approx(7.0, abs=1e-9)  # (0 + 14) / 2


def test_dihedral_floor_of_a_box_corner_point():
    # D2 (2-fold about z, flip about x) on a point off every axis: the orbit's median is the
    # centre (the group fixes only it), every copy |c| from it; a random copy lies farther.
    sym = {"axis": [0, 0, 1], "order": 2, "flip": [1, 0, 0], "point": [0, 0, 0]}
    c = np.array([3.0, 4.0, 12.0])
    floor, _, copy = sf.window_floor(sym, c)
    assert len(sf.group(sym)) == 4
    assert floor == pytest.approx(13.0, abs=1e-4)
    assert copy > floor


def test_order_zero_is_every_angle_and_all_is_the_sphere():
    ring = {"axis": [0, 0, 1], "order": 0, "point": [0, 0, 0]}
    assert len(sf.group(ring)) == 360
    floor, _, _ = sf.window_floor(ring, [10.0, 0.0, 2.0])
    assert floor == pytest.approx(10.0, rel=1e-3)  # the ring's median is its centre
    ball = {"all": True, "point": [1, 2, 3]}
    floor, _, copy = sf.window_floor(ball, [1.0, 2.0, 8.0])
    assert floor == pytest.approx(5.0, rel=1e-3)
    assert copy == pytest.approx(20.0 / 3, rel=5e-2)  # 4 r / 3 on average over the sphere


def test_the_surface_floor_is_at_least_the_floor(tmp_path):
    # A 20 x 10 x 6 box as binary PLY (the benchmark's layout), its D2 group, points on its faces.
    V = np.array([[x, y, z] for x in (-10, 10) for y in (-5, 5) for z in (-3, 3)], dtype="<f4")
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    path = tmp_path / "mesh.ply"
    with open(path, "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                b"property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n")
        f.write(V.tobytes())
        for t in tris:
            f.write(struct.pack("<B3i", 3, *t))
    Vr, T = sf.read_mesh(str(path))
    assert np.array_equal(Vr, V.astype(float)) and T.shape == (12, 3)
    S = sf.surface_samples(Vr, T, spacing_mm=1.0)
    assert len(S) >= 2 * (200 + 60 + 120) and np.all(np.abs(S) <= [10, 5, 3])
    sym = {"axis": [0, 0, 1], "order": 2, "flip": [1, 0, 0], "point": [0, 0, 0]}
    for c in ([4.0, 2.0, 3.0], [10.0, -1.0, 0.5], [-7.0, 5.0, -2.0]):
        floor, surface, copy = sf.window_floor(sym, c, S)
        # The median (the centre) lies 3 mm inside the nearest face: answering a point of the
        # surface costs more, and picking a copy at random more than the best surface point.
        assert floor < surface <= copy + 1.0  # the samples are 1 mm apart; c is one of the surface's points
