"""FPS and ball-query cases with the PyTorch reference's indices, for
tests/test_point_ops.cpp (which runs this with /usr/bin/python3 and reads the file).

usage: python3 tests/point_cases.py OUT.safetensors   (from the repository root)

Each case `<name>` holds `<name>.cloud` (N x 3 float32), `<name>.fps` (I32, npoint),
`<name>.ball.<s>` (I32, npoint x nsample) and `<name>.params` (float32: npoint,
then radius, nsample per scale). Clouds are chosen for ties: duplicates,
identical points, collinear points, a grid of exactly representable
coordinates (ball radius on the boundary), and sizes that are not powers of two.
"""
import sys

import torch

sys.path.insert(0, ".")
from weights_tools import pointnet2, safetensors_io  # noqa: E402


def cases():
    g = torch.Generator().manual_seed(5)
    rand = lambda n: torch.rand(n, 3, generator=g) * 2 - 1  # noqa: E731
    yield "random_1000", rand(1000), 200, [(0.2, 16), (0.5, 40)]
    base = rand(100)
    yield "duplicates", base[torch.arange(300) % 100], 150, [(0.3, 8)]  # 150 > 100 distinct: zeros, then index 0
    yield "identical", torch.full((37, 3), 0.25), 37, [(0.1, 5)]
    t = torch.linspace(-1, 1, 513)
    yield "collinear", torch.stack([t, 2 * t, -t], 1)[torch.randperm(513, generator=g)], 100, [(0.05, 6)]
    k = torch.arange(-4, 5, dtype=torch.float32) * 0.125  # exact: every squared distance is exact
    grid = torch.cartesian_prod(k, k, k)
    yield "grid", grid, 729, [(0.125, 7), (0.25, 33)]  # npoint = N; radii exactly on grid distances
    yield "n16", rand(16), 16, [(0.5, 4)]
    yield "n17", rand(17), 9, [(0.7, 20)]  # nsample > N: filled
    yield "n4097", rand(4097), 4097, [(0.1, 8)]
    yield "n16384", rand(16384), 512, [(0.1, 16), (0.4, 128)]


def main(out):
    tensors = {}
    for name, cloud, npoint, scales in cases():
        cloud = cloud.float().contiguous()
        fps = pointnet2.farthest_point_sample(cloud[None], npoint)[0]
        centres = cloud[fps]
        tensors[name + ".cloud"] = cloud
        tensors[name + ".fps"] = fps.int()
        params = [float(npoint)]
        for s, (r, ns) in enumerate(scales):
            tensors[f"{name}.ball.{s}"] = pointnet2.ball_query(cloud[None], centres[None], r, ns)[0].int()
            params += [r, float(ns)]
        tensors[name + ".params"] = torch.tensor(params, dtype=torch.float32)
    safetensors_io.save(out, tensors)


if __name__ == "__main__":
    main(sys.argv[1])
