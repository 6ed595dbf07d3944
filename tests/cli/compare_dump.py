"""Compares `vtloc localize --dump` tensors with a weights_tools.golden file.

  python3 tests/cli/compare_dump.py DUMP.safetensors GOLDEN.safetensors

Every tensor of the golden must be in the dump with the same shape; index
tensors must be equal, the rest within 2e-3 + 2e-3*|ref| (the engine runs
float32, the golden float64: the tolerance of tests/test_vtloc_model.cpp).
"""

import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the repository root
from weights_tools import safetensors_io  # noqa: E402


def main(dump_path, golden_path):
    dump, _ = safetensors_io.load(dump_path)
    gold, _ = safetensors_io.load(golden_path)
    bad = []
    for name, want in gold.items():
        got = dump.get(name)
        if got is None:
            bad.append(f"{name}: missing from the dump")
            continue
        if tuple(got.shape) != tuple(want.shape):
            bad.append(f"{name}: shape {tuple(got.shape)}, golden {tuple(want.shape)}")
            continue
        if not want.is_floating_point():
            if not torch.equal(got.to(torch.int64), want.to(torch.int64)):
                bad.append(f"{name}: indices differ")
            continue
        want = want.to(torch.float64)
        err = (got.to(torch.float64) - want).abs() - (2e-3 + 2e-3 * want.abs())
        if want.numel() and err.max().item() > 0:
            bad.append(f"{name}: off by up to {err.max().item():.3g} beyond the tolerance")
    for line in bad:
        print("compare_dump:", line, file=sys.stderr)
    print(f"compare_dump: {len(gold) - len(bad)} of {len(gold)} golden tensors match")
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
