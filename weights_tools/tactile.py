"""Tactile branch: preprocessing (SPEC 2) and the ResNet-18-topology encoder.

Module names mirror torchvision's resnet18 (conv1, bn1, layer{1..4}.{b}.conv1/bn1/
conv2/bn2/downsample.{0,1}) so a torchvision state_dict loads as is (minus fc).
"""

import torch
from torch import nn
import torch.nn.functional as F

from .layers import mlp

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)


def crop_start(size, crop):
    """First source row/column of torchvision's CenterCrop along one axis.

    Smaller images are zero padded by (crop - size) // 2 before the crop, so the
    start is negative; larger ones start at round((size - crop) / 2), with
    Python's round-half-to-even (what torchvision uses)."""
    if size < crop:
        return -((crop - size) // 2)
    return int(round((size - crop) / 2.0))


def center_crop(x, crop):
    """Centre crop (..., H, W) to crop x crop, zero filling outside the image."""
    h, w = x.shape[-2:]
    top, left = crop_start(h, crop), crop_start(w, crop)
    out = x.new_zeros(x.shape[:-2] + (crop, crop))
    # overlap of the crop window with the image, in source coordinates
    y0, y1 = max(top, 0), min(top + crop, h)
    x0, x1 = max(left, 0), min(left + crop, w)
    out[..., y0 - top:y1 - top, x0 - left:x1 - left] = x[..., y0:y1, x0:x1]
    return out


def preprocess(image_u8, crop, in_size, dtype=torch.float32):
    """uint8 H x W x 3 RGB -> 1 x 3 x in_size x in_size network input."""
    t = torch.as_tensor(image_u8)
    if t.dtype != torch.uint8 or t.dim() != 3 or t.shape[2] != 3:
        raise ValueError(f"expected uint8 H x W x 3, got {tuple(t.shape)} {t.dtype}")
    x = t.permute(2, 0, 1).to(dtype) / 255.0
    x = center_crop(x, crop).unsqueeze(0)
    if crop != in_size:
        x = F.interpolate(x, size=(in_size, in_size), mode="bilinear",
                          align_corners=False, antialias=False)
    mean = torch.tensor(IMAGENET_MEAN, dtype=dtype).view(1, 3, 1, 1)
    std = torch.tensor(IMAGENET_STD, dtype=dtype).view(1, 3, 1, 1)
    return (x - mean) / std


class BasicBlock(nn.Module):
    def __init__(self, inplanes, planes, stride):
        super().__init__()
        self.conv1 = nn.Conv2d(inplanes, planes, 3, stride, 1, bias=False)
        self.bn1 = nn.BatchNorm2d(planes)
        self.relu = nn.ReLU(inplace=False)
        self.conv2 = nn.Conv2d(planes, planes, 3, 1, 1, bias=False)
        self.bn2 = nn.BatchNorm2d(planes)
        self.downsample = None
        if stride != 1 or inplanes != planes:  # torchvision's rule
            self.downsample = nn.Sequential(nn.Conv2d(inplanes, planes, 1, stride, bias=False),
                                            nn.BatchNorm2d(planes))

    def forward(self, x):
        y = self.relu(self.bn1(self.conv1(x)))
        y = self.bn2(self.conv2(y))
        skip = x if self.downsample is None else self.downsample(x)
        return self.relu(y + skip)


class ResNetTrunk(nn.Module):
    """torchvision ResNet (BasicBlock) without fc; stem width = widths[0]."""

    def __init__(self, widths, blocks):
        super().__init__()
        self.conv1 = nn.Conv2d(3, widths[0], 7, 2, 3, bias=False)
        self.bn1 = nn.BatchNorm2d(widths[0])
        self.relu = nn.ReLU(inplace=False)
        self.maxpool = nn.MaxPool2d(3, 2, 1)
        inplanes = widths[0]
        for i, (planes, n) in enumerate(zip(widths, blocks)):
            stride = 1 if i == 0 else 2
            layer = []
            for b in range(n):
                layer.append(BasicBlock(inplanes, planes, stride if b == 0 else 1))
                inplanes = planes
            setattr(self, f"layer{i + 1}", nn.Sequential(*layer))
        self.avgpool = nn.AdaptiveAvgPool2d(1)
        self.out_channels = widths[-1]

    def forward(self, x):
        x = self.maxpool(self.relu(self.bn1(self.conv1(x))))
        x = self.layer4(self.layer3(self.layer2(self.layer1(x))))
        return torch.flatten(self.avgpool(x), 1)


class TactileEncoder(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        t = cfg["tactile"]
        self.backbone = ResNetTrunk(t["widths"], t["blocks"])
        self.mlp = mlp(t["widths"][-1], t["mlp"], cfg["C"])

    def forward(self, x):
        """B x 3 x S x S preprocessed images -> F^t (B x C)."""
        return self.mlp(self.backbone(x))
