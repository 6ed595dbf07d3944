"""Contact heads: the iterative localizing updater (ILU) and the MCR baseline."""

import torch
from torch import nn

from .config import MAX_ITERS
from .layers import mlp


class ILU(nn.Module):
    """Linear GRU over hidden size C; input order [h, x] for convz/convr/convq."""

    def __init__(self, cfg):
        super().__init__()
        C = cfg["C"]
        self.default_iters = cfg["ilu"]["iters"]
        self.convz = nn.Linear(3 * C, C)
        self.convr = nn.Linear(3 * C, C)
        self.convq = nn.Linear(3 * C, C)
        self.head = mlp(C, [cfg["ilu"]["head_hidden"]], 3)

    def forward(self, ft, fp, iters=None):
        """ft, fp: B x C -> c_1..c_N: B x N x 3 (N = 0 gives B x 0 x 3; c_0 = 0)."""
        n = self.default_iters if iters is None else int(iters)
        if not 0 <= n <= MAX_ITERS:
            raise ValueError(f"ILU iterations must be in 0..{MAX_ITERS}, got {n}")
        h = torch.tanh(ft)
        x = torch.cat([fp, torch.relu(ft)], dim=-1)
        c = ft.new_zeros(ft.shape[0], 3)
        cs = []
        for _ in range(n):
            hx = torch.cat([h, x], dim=-1)
            z = torch.sigmoid(self.convz(hx))
            r = torch.sigmoid(self.convr(hx))
            q = torch.tanh(self.convq(torch.cat([r * h, x], dim=-1)))
            h = (1 - z) * h + z * q
            c = c + self.head(h)
            cs.append(c)
        if not cs:
            return ft.new_zeros(ft.shape[0], 0, 3)
        return torch.stack(cs, dim=1)


class MCR(nn.Module):
    """c^p = tanh(MLP([F^t, F^p]))."""

    def __init__(self, cfg):
        super().__init__()
        self.decoder = mlp(2 * cfg["C"], cfg["mcr"]["hidden"], 3)

    def forward(self, fused):
        return torch.tanh(self.decoder(fused))
