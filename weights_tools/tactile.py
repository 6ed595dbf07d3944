"""Tactile branch: preprocessing (SPEC 2) and the ResNet-18-topology encoder.

Module names mirror torchvision's resnet18 (conv1, bn1, layer{1..4}.{b}.conv1/bn1/
conv2/bn2/downsample.{0,1}) so a torchvision state_dict loads as is (minus fc).
"""

import math

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


def check_mm_per_px(value, what="mm_per_px"):
    """A pixel size must be a finite number > 0 (mm)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or value <= 0:
        raise ValueError(f"{what} must be a finite number > 0, got {value!r}")
    return float(value)


def rescaled_size(n, image_mm, model_mm):
    """Side of a rescaled frame: round(n * image_mm / model_mm), halves up, at least 1."""
    return max(1, int(math.floor(n * image_mm / model_mm + 0.5)))


def _axis_taps(n_in, n_out, f):
    """Source pixels and weights of each output pixel along one axis; ``f`` =
    source pixels per output pixel (model_mm / image_mm).  Centres line up
    (the frame's centre stays the centre) and one output pixel spans exactly f
    source pixels, so millimetres are kept even where n_out * f != n_in.

    f > 1 (shrinking): area average of the source interval the output pixel
    covers, clipped to the image and renormalised there.  f < 1 (enlarging):
    bilinear between the two nearest source pixel centres, clamped at the
    edges.  The arithmetic is op for op the engine's (engine/api/rescale.cpp)."""
    taps = []
    for o in range(n_out):
        if f > 1:
            lo = n_in / 2 + (o - n_out / 2) * f
            hi = n_in / 2 + (o + 1 - n_out / 2) * f
            a, b = max(lo, 0.0), min(hi, float(n_in))
            if not b > a:  # cannot happen for n_out = round(n_in / f); nearest pixel
                i = min(max(int(math.floor(lo)), 0), n_in - 1)
                taps.append([(i, 1.0)])
                continue
            span = b - a
            row = []
            for i in range(int(math.floor(a)), int(math.ceil(b))):
                w = min(i + 1.0, b) - max(float(i), a)
                if w > 0:
                    row.append((i, w / span))
            taps.append(row)
        else:
            src = n_in / 2 + (o + 0.5 - n_out / 2) * f - 0.5
            src = min(max(src, 0.0), n_in - 1.0)
            i0 = int(math.floor(src))
            i1 = min(i0 + 1, n_in - 1)
            w1 = src - i0
            taps.append([(i0, 1.0 - w1), (i1, w1)])
    width = max(len(t) for t in taps)
    index = torch.zeros(n_out, width, dtype=torch.long)
    weight = torch.zeros(n_out, width, dtype=torch.float64)
    for o, row in enumerate(taps):
        for j, (i, w) in enumerate(row):
            index[o, j], weight[o, j] = i, w
    return index, weight


def rescale(image_u8, image_mm, model_mm):
    """Resample a uint8 H x W x 3 frame taken with pixels of ``image_mm`` to
    pixels of ``model_mm`` (SPEC 2, sensor rescale; before the crop).  Output
    size round(H * s) x round(W * s), s = image_mm / model_mm; rows are
    resampled first, then columns, in float64 summing the taps in order, and
    the result is rounded (halves up) to uint8.  Equal pixel sizes return the
    frame unchanged."""
    image_mm, model_mm = check_mm_per_px(image_mm), check_mm_per_px(model_mm)
    t = torch.as_tensor(image_u8)
    if t.dtype != torch.uint8 or t.dim() != 3 or t.shape[2] != 3:
        raise ValueError(f"expected uint8 H x W x 3, got {tuple(t.shape)} {t.dtype}")
    if image_mm == model_mm:
        return t
    h, w = t.shape[:2]
    f = model_mm / image_mm
    oh, ow = rescaled_size(h, image_mm, model_mm), rescaled_size(w, image_mm, model_mm)
    x = t.to(torch.float64)
    ix, wx = _axis_taps(w, ow, f)
    row = torch.zeros(h, ow, 3, dtype=torch.float64)
    for j in range(ix.shape[1]):  # along each row (x) first
        row = row + wx[:, j].view(1, ow, 1) * x[:, ix[:, j], :]
    iy, wy = _axis_taps(h, oh, f)
    out = torch.zeros(oh, ow, 3, dtype=torch.float64)
    for j in range(iy.shape[1]):  # then along each column (y)
        out = out + wy[:, j].view(oh, 1, 1) * row[iy[:, j], :, :]
    return torch.floor(out + 0.5).clamp(0, 255).to(torch.uint8)


def sensor_rescale(image_u8, cfg, mm_per_px, source="the model"):
    """The frame as the model sees it: rescaled from ``mm_per_px`` to the
    config's ``sensor.mm_per_px``; unchanged when ``mm_per_px`` is None."""
    if mm_per_px is None:
        return torch.as_tensor(image_u8)
    mm_per_px = check_mm_per_px(mm_per_px)
    sensor = cfg.get("sensor")
    if sensor is None:
        raise ValueError(f"{source} has no sensor pixel size in its config; cannot rescale")
    return rescale(image_u8, mm_per_px, sensor["mm_per_px"])


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
