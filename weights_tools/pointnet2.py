"""PointNet++ point encoder (MSG, or SSG = one scale) with SPEC 2 semantics.

Index selection (FPS, ball query) always runs in float32 on the float32
coordinates, with squared distances summed as (dx*dx + dy*dy) + dz*dz, so an
engine doing the same single-precision arithmetic picks the same indices even
when the network itself runs in float64.  Nothing here is random.
"""

import torch
from torch import nn

from .layers import mlp


def sqdist(a, b):
    """Squared distance with a fixed summation order (broadcasting a - b)."""
    d = a - b
    return (d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) + d[..., 2] * d[..., 2]


def farthest_point_sample(xyz, npoint):
    """xyz: B x N x 3.  Start at index 0; each step take the point whose minimum
    squared distance to the chosen set is largest, lowest index on a tie."""
    xyz = xyz.float()
    B, N, _ = xyz.shape
    dev = xyz.device  # the reference also runs on a GPU (bench_torch --device)
    rows = torch.arange(B, device=dev)
    order = torch.arange(N, device=dev).expand(B, N)
    out = torch.zeros(B, npoint, dtype=torch.long, device=dev)
    mind = torch.full((B, N), float("inf"), dtype=torch.float32, device=dev)
    far = torch.zeros(B, dtype=torch.long, device=dev)
    for i in range(npoint):
        out[:, i] = far
        mind = torch.minimum(mind, sqdist(xyz, xyz[rows, far][:, None, :]))
        best = mind.max(dim=1, keepdim=True).values
        # explicit lowest-index tie break rather than relying on argmax
        far = torch.where(mind == best, order, N).min(dim=1).values
    return out


def ball_query(xyz, centres, radius, nsample):
    """xyz: B x N x 3, centres: B x S x 3 -> B x S x nsample indices: the first
    nsample points (index order) with d^2 <= r^2, r^2 = float32(r) * float32(r);
    empty slots repeat the first point found."""
    xyz, centres = xyz.float(), centres.float()
    N = xyz.shape[1]
    r = torch.tensor(radius, dtype=torch.float32, device=xyz.device)
    d = sqdist(xyz[:, None, :, :], centres[:, :, None, :])  # B x S x N
    idx = torch.where(d <= r * r, torch.arange(N, device=xyz.device), N)
    idx = idx.sort(dim=-1).values[..., :nsample]
    if idx.shape[-1] < nsample:  # fewer points than nsample in the whole cloud
        pad = idx.new_full(idx.shape[:-1] + (nsample - idx.shape[-1],), N)
        idx = torch.cat([idx, pad], dim=-1)
    return torch.where(idx == N, idx[..., :1], idx)


def gather(x, idx):
    """x: B x N x C, idx: B x ... -> B x ... x C."""
    B = x.shape[0]
    flat = idx.reshape(B, -1)
    out = torch.gather(x, 1, flat[..., None].expand(-1, -1, x.shape[-1]))
    return out.reshape(idx.shape + (x.shape[-1],))


def conv_bn_stack(in_ch, widths):
    convs, bns = nn.ModuleList(), nn.ModuleList()
    for w in widths:
        convs.append(nn.Conv2d(in_ch, w, 1))
        bns.append(nn.BatchNorm2d(w))
        in_ch = w
    return convs, bns


def run_stack(x, convs, bns):
    for conv, bn in zip(convs, bns):
        x = torch.relu(bn(conv(x)))
    return x


class SetAbstraction(nn.Module):
    """Multi-scale grouping stage (names conv_blocks.{scale}.{layer}, bn_blocks...)."""

    def __init__(self, stage, in_feat):
        super().__init__()
        self.npoint = stage["npoint"]
        self.radii = stage["radii"]
        self.nsample = stage["nsample"]
        self.conv_blocks, self.bn_blocks = nn.ModuleList(), nn.ModuleList()
        for widths in stage["mlps"]:
            convs, bns = conv_bn_stack(in_feat + 3, widths)
            self.conv_blocks.append(convs)
            self.bn_blocks.append(bns)
        self.out_channels = sum(m[-1] for m in stage["mlps"])

    def forward(self, xyz, feats):
        """xyz: B x N x 3, feats: B x N x C or None.
        Returns new_xyz (B x S x 3), new feats (B x S x C'), fps (B x S), balls."""
        fps = farthest_point_sample(xyz, self.npoint)
        new_xyz = gather(xyz, fps)
        outs, balls = [], []
        for s, (radius, ns) in enumerate(zip(self.radii, self.nsample)):
            idx = ball_query(xyz, new_xyz, radius, ns)
            balls.append(idx)
            rel = gather(xyz, idx) - new_xyz[:, :, None, :]  # B x S x ns x 3
            grouped = rel if feats is None else torch.cat([gather(feats, idx), rel], dim=-1)
            x = run_stack(grouped.permute(0, 3, 2, 1), self.conv_blocks[s], self.bn_blocks[s])
            outs.append(x.max(dim=2).values)  # max over neighbours: B x C x S
        return new_xyz, torch.cat(outs, dim=1).transpose(1, 2), fps, balls


class GroupAll(nn.Module):
    """Last stage: one group of all points, input [xyz, feats], xyz not centred."""

    def __init__(self, widths, in_feat):
        super().__init__()
        self.mlp_convs, self.mlp_bns = conv_bn_stack(in_feat + 3, widths)

    def forward(self, xyz, feats):
        x = torch.cat([xyz, feats], dim=-1).transpose(1, 2)[:, :, :, None]  # B x C x N x 1
        return run_stack(x, self.mlp_convs, self.mlp_bns).amax(dim=(2, 3))


class PointEncoder(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        p = cfg["point"]
        self.use_normals = p["use_normals"]
        c = 3 if self.use_normals else 0
        self.n_stages = len(p["sa"])
        for i, stage in enumerate(p["sa"]):
            sa = SetAbstraction(stage, c)
            setattr(self, f"sa{i + 1}", sa)
            c = sa.out_channels
        setattr(self, f"sa{self.n_stages + 1}", GroupAll(p["group_all_mlp"], c))
        self.mlp = mlp(p["group_all_mlp"][-1], p["mlp"], cfg["C"])

    def forward(self, cloud, trace=None):
        """cloud: B x N x 6 (xyz, normals) or B x N x 3, normalised frame -> F^p (B x C).
        ``trace``: optional dict that receives fps / ball indices per stage."""
        xyz = cloud[..., :3]
        feats = cloud[..., 3:6] if self.use_normals else None
        if self.use_normals and cloud.shape[-1] < 6:
            raise ValueError("this config uses normals: cloud must be B x N x 6")
        for i in range(1, self.n_stages + 1):
            xyz, feats, fps, balls = getattr(self, f"sa{i}")(xyz, feats)
            if trace is not None:
                trace[f"point.sa{i}.fps"] = fps
                for s, b in enumerate(balls):
                    trace[f"point.sa{i}.ball.{s}"] = b
        x = getattr(self, f"sa{self.n_stages + 1}")(xyz, feats)
        return self.mlp(x)
