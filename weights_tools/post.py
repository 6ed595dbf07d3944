"""After the network (SPEC 1, 3, 6): normalised frame, candidate top-K,
heat-map, symmetry prior and Chamfer distance.

Everything here takes tensors for one object (no batch dimension) and works in
the normalised frame unless said otherwise.
"""

import math

import torch

from .pointnet2 import sqdist


def normalisation(xyz):
    """centre = mean(xyz), scale = max ||p - centre||, computed in float64."""
    p = torch.as_tensor(xyz).double()
    centre = p.mean(dim=0)
    scale = torch.linalg.vector_norm(p - centre, dim=-1).max()
    if not scale > 0:
        raise ValueError("degenerate cloud: all points coincide")
    return centre, scale


def normalise_points(xyz, centre, scale):
    """Object units -> normalised frame (float64 arithmetic, float32 result)."""
    return ((torch.as_tensor(xyz).double() - centre) / scale).float()


def normalise_cloud(cloud):
    """N x 6 (or N x 3) object-unit cloud -> (normalised float32 cloud, centre, scale).
    Normals are copied unchanged."""
    cloud = torch.as_tensor(cloud)
    centre, scale = normalisation(cloud[:, :3])
    out = cloud.float().clone()
    out[:, :3] = normalise_points(cloud[:, :3], centre, scale)
    return out, centre, scale


def candidate_scores(contact, candidates):
    """S_i = ||c^p - c_i||^2 in float32, summed (dx*dx + dy*dy) + dz*dz."""
    return sqdist(candidates.float(), contact.float().reshape(1, 3))


def top_k(contact, candidates, k):
    """Indices (ascending score, ties to the lower index) and scores of the K best."""
    s = candidate_scores(contact, candidates)
    order = torch.sort(s, stable=True).indices[:min(k, s.numel())]
    return order, s[order]


def rotate_about_axis(points, axis_point, axis_dir, angle):
    """Rotate M x 3 points by ``angle`` (right-handed about axis_dir) about a line."""
    p = torch.as_tensor(points).double()
    a = torch.as_tensor(axis_point).double()
    k = torch.as_tensor(axis_dir).double()
    k = k / torch.linalg.vector_norm(k)
    v = p - a
    cos, sin = math.cos(angle), math.sin(angle)
    # Rodrigues: v cos + (k x v) sin + k (k . v)(1 - cos)
    kv = torch.linalg.cross(k.expand_as(v), v, dim=-1)
    rot = v * cos + kv * sin + k * (v @ k)[:, None] * (1 - cos)
    return rot + a


def symmetric_copies(points, ranks, axis_point, axis_dir, order):
    """Each point replaced by its ``order`` copies rotated by 360/order degrees,
    each copy keeping its rank.  Returns (points, ranks) grouped by input point,
    copy 0 being the point itself."""
    pts, rks = [], []
    for j in range(points.shape[0]):
        for m in range(order):
            pts.append(rotate_about_axis(points[j:j + 1], axis_point, axis_dir,
                                         2 * math.pi * m / order))
            rks.append(ranks[j])
    return torch.cat(pts).to(points.dtype), torch.as_tensor(rks, dtype=torch.long)


def heatmap(cloud_xyz, centres, ranks=None, symmetry=None):
    """Heat-map over the cloud's points (float64 arithmetic, float32 result).

    ``centres``: c*_1..c*_K in rank order (ranks 1..K) unless ``ranks`` (1-based)
    is given.  ``symmetry``: optional (axis_point, axis_dir, order) in the
    normalised frame.  s_p = exp(-||p - c*_w||) / w with w the rank of the
    nearest centre (lowest rank on a tie), then min-max normalised (all zeros
    when max == min)."""
    c = torch.as_tensor(centres).double()
    r = torch.arange(1, c.shape[0] + 1, device=c.device) if ranks is None else torch.as_tensor(ranks, device=c.device)
    if symmetry is not None:
        c, r = symmetric_copies(c, r, *symmetry)
    # sort by rank (stable) so the first minimum is the lowest rank
    order = torch.sort(r, stable=True).indices
    c, r = c[order], r[order]
    p = torch.as_tensor(cloud_xyz).double()[:, :3]
    d = torch.sqrt(sqdist(p[:, None, :], c[None, :, :]))  # N x M
    dmin, w = d.min(dim=1)
    # torch.min's index on ties is not documented: take the first minimum explicitly
    w = torch.where(d == dmin[:, None], torch.arange(c.shape[0], device=d.device), c.shape[0]).min(dim=1).values
    s = torch.exp(-dmin) / r[w].double()
    lo, hi = s.min(), s.max()
    if hi == lo:
        return torch.zeros(p.shape[0], dtype=torch.float32, device=p.device)
    return ((s - lo) / (hi - lo)).float()


def chamfer(a, b):
    """mean_a min_b ||a-b||^2 + mean_b min_a ||a-b||^2 for equal-width rows,
    in float64 (returned as a 0-dim float64 tensor)."""
    a, b = torch.as_tensor(a).double(), torch.as_tensor(b).double()
    if a.shape[-1] != b.shape[-1]:
        raise ValueError("chamfer: point sets need the same width")
    diff = a[:, None, :] - b[None, :, :]
    d = (diff * diff).sum(dim=-1)
    return d.min(dim=1).values.mean() + d.min(dim=0).values.mean()
