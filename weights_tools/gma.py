"""Geometric multi-modal alignment: fused feature -> pseudo point cloud P^d."""

import torch
from torch import nn
import torch.nn.functional as F

from .layers import mlp

SLOPE = 0.01  # LeakyReLU negative slope (SPEC 2)


class GMA(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        g = cfg["gma"]
        # W^d: 2C x N^d x C^d, stored as is ("gma.weight")
        self.weight = nn.Parameter(torch.empty(2 * cfg["C"], g["n_points"], g["channels"]))
        nn.init.normal_(self.weight, std=(2 * cfg["C"]) ** -0.5)
        self.decoder = mlp(g["channels"], g["decoder"], 6, act=lambda: nn.LeakyReLU(SLOPE))

    def forward(self, fused):
        """fused: B x 2C ([F^t, F^p]) -> P^d: B x N^d x 6 (xyz in (-1, 1), unit normals)."""
        fd = F.leaky_relu(torch.einsum("bi,ijl->bjl", fused, self.weight), SLOPE)
        o = self.decoder(fd)
        n = o[..., 3:6]
        norm = torch.linalg.vector_norm(n, dim=-1, keepdim=True).clamp_min(1e-6)
        return torch.cat([torch.tanh(o[..., 0:3]), n / norm], dim=-1)
