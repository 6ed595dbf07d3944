"""Deterministic synthetic inputs (documented in README.md).

Random numbers come from SplitMix64 (exact integer arithmetic), so a seed gives
the same parameters on every platform and the definitions can be re-implemented
elsewhere; shapes are then evaluated in float64 and rounded once.
"""

import math

import numpy as np

_MASK = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed):
        self.state = int(seed) & _MASK

    def next_u64(self):
        self.state = (self.state + 0x9E3779B97F4A7C15) & _MASK
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK
        return z ^ (z >> 31)

    def uniform(self, lo=0.0, hi=1.0):
        """Uniform in [lo, hi) from the top 53 bits."""
        return lo + (hi - lo) * ((self.next_u64() >> 11) * 2.0 ** -53)


def _spow(x, e):
    """sign(x) |x|^e."""
    return np.sign(x) * np.abs(x) ** e


def superellipsoid_cloud(seed, n):
    """N x 6 float32 (xyz in mm, unit normals) on a random superellipsoid.

    Draw order: semi-axes a, b, c in [20, 60) mm; exponents e1, e2 in [0.4, 1.0);
    yaw in [0, 2 pi); offset x, y, z in [-30, 30) mm; then per point u in
    [-pi, pi), w in [0, 1) with v = asin(2 w - 1)."""
    rng = SplitMix64(seed)
    a, b, c = (rng.uniform(20, 60) for _ in range(3))
    e1, e2 = rng.uniform(0.4, 1.0), rng.uniform(0.4, 1.0)
    yaw = rng.uniform(0, 2 * math.pi)
    offset = np.array([rng.uniform(-30, 30) for _ in range(3)])
    uv = np.array([(rng.uniform(-math.pi, math.pi), math.asin(2 * rng.uniform() - 1))
                   for _ in range(n)], dtype=np.float64).reshape(n, 2)
    u, v = uv[:, 0], uv[:, 1]
    cu, su, cv, sv = np.cos(u), np.sin(u), np.cos(v), np.sin(v)
    xyz = np.stack([a * _spow(cv, e1) * _spow(cu, e2),
                    b * _spow(cv, e1) * _spow(su, e2),
                    c * _spow(sv, e1)], axis=1)
    # normal of the parametric superellipsoid: (cos^(2-e) terms) / semi-axis
    nrm = np.stack([_spow(cv, 2 - e1) * _spow(cu, 2 - e2) / a,
                    _spow(cv, 2 - e1) * _spow(su, 2 - e2) / b,
                    _spow(sv, 2 - e1) / c], axis=1)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    rot = np.array([[math.cos(yaw), -math.sin(yaw), 0.0],
                    [math.sin(yaw), math.cos(yaw), 0.0],
                    [0.0, 0.0, 1.0]])
    xyz = xyz @ rot.T + offset
    nrm = nrm @ rot.T
    return np.concatenate([xyz, nrm], axis=1).astype(np.float32)


def tactile_image(seed, height=120, width=160):
    """H x W x 3 uint8 GelSight-like frame: a Gaussian indentation shaded by its
    gradient (R: d/dx, G: d/dy, B: depth) and a grid of dark markers.

    Draw order: base R, G, B in [90, 150); centre row cy = H * [0.3, 0.7),
    column cx = W * [0.3, 0.7); sigma in [8, 20) px; depth A in [0.5, 1.0);
    marker phase oy, ox in [0, 16) px."""
    rng = SplitMix64(seed)
    base = np.array([rng.uniform(90, 150) for _ in range(3)])
    cy, cx = height * rng.uniform(0.3, 0.7), width * rng.uniform(0.3, 0.7)
    sigma, amp = rng.uniform(8, 20), rng.uniform(0.5, 1.0)
    oy, ox = rng.uniform(0, 16), rng.uniform(0, 16)
    y, x = np.meshgrid(np.arange(height, dtype=np.float64),
                       np.arange(width, dtype=np.float64), indexing="ij")
    g = amp * np.exp(-((y - cy) ** 2 + (x - cx) ** 2) / (2 * sigma ** 2))
    gx, gy = -(x - cx) / sigma * g, -(y - cy) / sigma * g  # sigma * d/dx of the depth
    img = np.stack([base[0] + 150 * gx, base[1] + 150 * gy, base[2] + 80 * g], axis=-1)
    my = np.mod(y - oy + 8, 16) - 8
    mx = np.mod(x - ox + 8, 16) - 8
    marker = 1 - 0.7 * np.exp(-(my ** 2 + mx ** 2) / (2 * 1.2 ** 2))
    img *= marker[..., None]
    return np.rint(np.clip(img, 0, 255)).astype(np.uint8)
