"""The paper config (vtloc-r18): names and shapes of SPEC 7, torchvision compatibility.
Instantiated once for the module; never run at full size."""

import re

import pytest
import torch
import torchvision

from weights_tools import config
from weights_tools.model import VTLoc


@pytest.fixture(scope="module")
def paper():
    torch.manual_seed(0)
    return VTLoc(config.named("vtloc-r18"))


def test_backbone_loads_into_torchvision(paper):
    sd = {k[len("tactile.backbone."):]: v for k, v in paper.state_dict().items()
          if k.startswith("tactile.backbone.")}
    ref = torchvision.models.resnet18()
    res = ref.load_state_dict(sd, strict=False)  # raises on any shape mismatch
    assert sorted(res.missing_keys) == ["fc.bias", "fc.weight"]
    assert res.unexpected_keys == []
    assert set(sd) == set(ref.state_dict()) - {"fc.weight", "fc.bias"}


def test_backbone_matches_torchvision_numerically(paper):
    backbone = paper.tactile.backbone
    g = torch.Generator().manual_seed(1)
    state = {}
    for k, v in backbone.state_dict().items():
        if k.endswith("running_var"):
            state[k] = torch.rand(v.shape, generator=g) + 0.5
        elif v.is_floating_point():
            state[k] = torch.randn(v.shape, generator=g) * (0.1 if "conv" in k else 1)
        else:
            state[k] = v
    ref = torchvision.models.resnet18()
    ref.fc = torch.nn.Identity()
    ref.load_state_dict(state)
    backbone = type(backbone)([64, 128, 256, 512], [2, 2, 2, 2])
    backbone.load_state_dict(state)
    x = torch.randn(1, 3, 64, 64, generator=g)
    with torch.no_grad():
        assert torch.allclose(backbone.eval()(x), ref.eval()(x), rtol=1e-5, atol=1e-5)


def test_spec7_names_and_shapes(paper):
    sd = paper.state_dict()
    patterns = [
        r"tactile\.backbone\..*",
        r"tactile\.mlp\.[02]\.(weight|bias)",
        r"point\.sa[12]\.conv_blocks\.[0-2]\.[0-2]\.(weight|bias)",
        r"point\.sa[12]\.bn_blocks\.[0-2]\.[0-2]\.(weight|bias|running_mean|running_var|num_batches_tracked)",
        r"point\.sa3\.mlp_convs\.[0-2]\.(weight|bias)",
        r"point\.sa3\.mlp_bns\.[0-2]\.(weight|bias|running_mean|running_var|num_batches_tracked)",
        r"point\.mlp\.[02]\.(weight|bias)",
        r"gma\.weight", r"gma\.decoder\.[0246]\.(weight|bias)",
        r"ilu\.conv[zrq]\.(weight|bias)", r"ilu\.head\.[02]\.(weight|bias)",
    ]
    for k in sd:
        assert any(re.fullmatch(p, k) for p in patterns), k
    shapes = {
        "tactile.mlp.0.weight": (256, 512), "tactile.mlp.2.weight": (128, 256),
        "point.sa1.conv_blocks.0.0.weight": (32, 6, 1, 1),
        "point.sa1.conv_blocks.2.1.weight": (96, 64, 1, 1),
        "point.sa2.conv_blocks.0.0.weight": (64, 323, 1, 1),
        "point.sa3.mlp_convs.0.weight": (256, 643, 1, 1),
        "point.sa3.mlp_convs.2.weight": (1024, 512, 1, 1),
        "point.mlp.0.weight": (512, 1024), "point.mlp.2.weight": (128, 512),
        "gma.weight": (256, 1024, 64), "gma.decoder.0.weight": (64, 64),
        "gma.decoder.6.weight": (6, 16),
        "ilu.convz.weight": (128, 384), "ilu.convq.bias": (128,),
        "ilu.head.0.weight": (64, 128), "ilu.head.2.weight": (3, 64),
    }
    for k, s in shapes.items():
        assert tuple(sd[k].shape) == s, k
    assert not any(k.startswith("mcr.") for k in sd)


def test_mcr_config_names():
    cfg = config.named("vtloc-mcr")
    assert cfg["point"]["use_normals"] is False and cfg["gma"] is None and cfg["ilu"] is None
    assert cfg["mcr"] == {"hidden": [256, 32]} and cfg["head"] == "mcr"
    # the MCR head alone (building the whole model would repeat the paper encoders)
    from weights_tools.ilu import MCR
    names = {k: tuple(v.shape) for k, v in MCR(cfg).state_dict().items()}
    assert names == {"decoder.0.weight": (256, 256), "decoder.0.bias": (256,),
                     "decoder.2.weight": (32, 256), "decoder.2.bias": (32,),
                     "decoder.4.weight": (3, 32), "decoder.4.bias": (3,)}
