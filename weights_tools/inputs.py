"""Reading user inputs: tactile images and point files."""

import sys

import numpy as np
import torch

from .ply import read_ply


def read_tactile(path):
    """Image file -> H x W x 3 uint8 RGB (alpha dropped, grey expanded)."""
    try:
        from torchvision.io import ImageReadMode, read_image
        return read_image(str(path), ImageReadMode.RGB).permute(1, 2, 0).contiguous().numpy()
    except (ImportError, RuntimeError):
        from PIL import Image  # torchvision built without image support
        with Image.open(path) as im:
            return np.asarray(im.convert("RGB"), dtype=np.uint8).copy()


def read_points(path):
    """.ply, .npy or text (whitespace/comma separated rows, '#' comments) -> float32 N x D."""
    p = str(path)
    if p.endswith(".ply"):
        return read_ply(p)
    if p.endswith(".npy"):
        return np.load(p).astype(np.float32)
    rows = []
    with open(p) as f:
        for line in f:
            line = line.split("#", 1)[0].replace(",", " ").split()
            if line:
                rows.append([float(v) for v in line])
    return np.array(rows, dtype=np.float32).reshape(len(rows), -1)


def read_cloud(path):
    """Point cloud file -> N x 6 float32 (xyz, normals); missing normals become zeros."""
    pts = read_points(path)
    if pts.ndim != 2 or pts.shape[1] not in (3, 6):
        raise ValueError(f"{path}: expected N x 3 or N x 6 points, got {pts.shape}")
    if pts.shape[1] == 3:
        print(f"warning: {path} has no normals; using zeros", file=sys.stderr)
        pts = np.concatenate([pts, np.zeros_like(pts)], axis=1)
    return torch.from_numpy(pts)


def read_candidates(path):
    """Candidate contact points (object units) -> M x 3 float32 (extra columns dropped)."""
    pts = read_points(path)
    if pts.ndim != 2 or pts.shape[1] < 3 or len(pts) == 0:
        raise ValueError(f"{path}: expected M x 3 candidate points, got {pts.shape}")
    return torch.from_numpy(np.ascontiguousarray(pts[:, :3]))
