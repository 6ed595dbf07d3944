"""The whole VTLoc network; ``model.state_dict()`` is the weight file (SPEC 7)."""

import json

import torch
from torch import nn

from . import config as config_mod
from . import safetensors_io
from .gma import GMA
from .ilu import ILU, MCR
from .pointnet2 import PointEncoder
from .tactile import TactileEncoder

CONFIG_KEY = "vtloc.config"


class VTLoc(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        self.cfg = config_mod.canonical(cfg)
        self.tactile = TactileEncoder(self.cfg)
        self.point = PointEncoder(self.cfg)
        # optional parts exist only when configured, so their names are absent otherwise
        if self.cfg["gma"] is not None:
            self.gma = GMA(self.cfg)
        if self.cfg["ilu"] is not None:
            self.ilu = ILU(self.cfg)
        if self.cfg["mcr"] is not None:
            self.mcr = MCR(self.cfg)
        self.eval()

    def has(self, part):
        return part in self._modules

    def contact(self, ft, fp, iters=None):
        """Returns (c^p: B x 3, c_1..c_N: B x N x 3 or None)."""
        if self.cfg["head"] == "mcr":
            return self.mcr(torch.cat([ft, fp], dim=-1)), None
        cs = self.ilu(ft, fp, iters)
        cp = cs[:, -1] if cs.shape[1] else ft.new_zeros(ft.shape[0], 3)
        return cp, cs

    def forward(self, image, cloud, iters=None, trace=None):
        """image: B x 3 x S x S preprocessed; cloud: B x N x 6 (or x 3) normalised.
        Returns a dict of outputs named as in SPEC 8 (with a batch dimension)."""
        out = {} if trace is None else trace
        ft = self.tactile(image)
        fp = self.point(cloud, trace=out)
        out["tactile.feature"], out["point.feature"] = ft, fp
        if self.has("gma"):
            out["gma.cloud"] = self.gma(torch.cat([ft, fp], dim=-1))
        cp, cs = self.contact(ft, fp, iters)
        if cs is not None:
            out["ilu.c"] = cs
        out["contact"] = cp
        return out


def config_metadata(cfg):
    return {CONFIG_KEY: config_mod.to_json(cfg), "format": "pt"}


def fill_missing_counters(model, state):
    """Weight files may omit BatchNorm's num_batches_tracked (the engine ignores it)."""
    state = dict(state)
    for k, v in model.state_dict().items():
        if k.endswith("num_batches_tracked") and k not in state:
            state[k] = torch.zeros_like(v)
    return state


def load_state(model, state):
    """Strict load with float tensors cast to the model's dtype."""
    own = model.state_dict()
    state = fill_missing_counters(model, state)
    cast = {k: (v.to(own[k].dtype) if k in own and v.is_floating_point() else v)
            for k, v in state.items()}
    model.load_state_dict(cast, strict=True)
    return model


def load(path):
    """Build the model described by a weight file's metadata and load its tensors."""
    tensors, meta = safetensors_io.load(path)
    if CONFIG_KEY not in meta:
        raise ValueError(f"{path}: no {CONFIG_KEY} in __metadata__")
    model = VTLoc(json.loads(meta[CONFIG_KEY]))
    return load_state(model, tensors)


def save(model, path, dtype=torch.float32):
    """Write model.state_dict() (floats as ``dtype``, integer counters as I64)."""
    sd = {k: (v.to(dtype) if v.is_floating_point() else v)
          for k, v in model.state_dict().items()}
    safetensors_io.save(path, sd, config_metadata(model.cfg))
