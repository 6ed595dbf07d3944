"""Regenerate the committed goldens (byte for byte):

  python3 -m weights_tools.make_goldens [--out weights_tools/goldens]
  python3 -m weights_tools.make_goldens --paper --out build/goldens

--paper writes the paper-size configs (vtloc-r18, vtloc-mcr; ~120 MB of
weights, so not committed) and skips the work when its outputs are newer
than every weights_tools source file.

For each small config: random weights (seed 0) -> NAME.safetensors, and a
golden run on synthetic tactile seed 0 / synthetic cloud seed 0 with the
config's defaults (ILU iterations, K, candidates = the cloud) ->
NAME.golden.safetensors.

The sensor fixture vtloc-tiny-sensor (vtloc-tiny plus a sensor of 0.1245 mm
pixels, the same tensors) gets its weights and one golden per frame pixel size
in SENSOR_GOLDENS: the synthetic frame taken as coarser pixels (enlarged before
the crop, bilinear) and as finer ones (shrunk, area average) ->
vtloc-tiny-sensor.{coarse,fine}.golden.safetensors.
"""

import argparse
import os
import sys

import torch

from . import config, golden, model
from .export import random_model

CONFIGS = ("vtloc-tiny", "vtloc-mcr-tiny")
PAPER_CONFIGS = ("vtloc-r18", "vtloc-mcr")
SENSOR_CONFIG = "vtloc-tiny-sensor"
SENSOR_GOLDENS = (("coarse", 0.166), ("fine", 0.083))  # frame mm per pixel (the model's: 0.1245)
DEFAULT_OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "goldens")


def make_all(out_dir, names=CONFIGS, sensor=True):
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # one fixed reduction order
    try:
        os.makedirs(out_dir, exist_ok=True)
        written = []
        for name in names:
            w = os.path.join(out_dir, f"{name}.safetensors")
            # Paper-size weights are not committed but made where they are tested:
            # calibrated in float32 there (7 s against 17 s for the two configs).
            dtype = torch.float32 if name in PAPER_CONFIGS else torch.float64
            model.save(random_model(config.named(name), seed=0, dtype=dtype), w)
            g = os.path.join(out_dir, f"{name}.golden.safetensors")
            tensors, meta, cfg = golden.make(w, synthetic_tactile=0, synthetic_cloud=0)
            golden.write(g, tensors, cfg, meta)
            written += [w, g]
        if sensor:
            w = os.path.join(out_dir, f"{SENSOR_CONFIG}.safetensors")
            model.save(random_model(config.named(SENSOR_CONFIG), seed=0), w)
            written.append(w)
            for label, mm in SENSOR_GOLDENS:
                g = os.path.join(out_dir, f"{SENSOR_CONFIG}.{label}.golden.safetensors")
                tensors, meta, cfg = golden.make(w, synthetic_tactile=0, synthetic_cloud=0, mm_per_px=mm)
                golden.write(g, tensors, cfg, meta)
                written.append(g)
        return written
    finally:
        torch.set_num_threads(threads)


def outputs(out_dir, names):
    return [os.path.join(out_dir, f"{n}{suffix}.safetensors") for n in names for suffix in ("", ".golden")]


def up_to_date(paths):
    """All paths exist and are newer than every source file of this package."""
    here = os.path.dirname(os.path.abspath(__file__))
    newest_src = max(os.path.getmtime(os.path.join(here, f)) for f in os.listdir(here) if f.endswith(".py"))
    return all(os.path.exists(p) and os.path.getmtime(p) > newest_src for p in paths)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m weights_tools.make_goldens", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=DEFAULT_OUT)
    ap.add_argument("--paper", action="store_true", help="the paper-size configs instead of the tiny ones")
    a = ap.parse_args(argv)
    names = PAPER_CONFIGS if a.paper else CONFIGS
    if a.paper and up_to_date(outputs(a.out, names)):
        print(f"paper goldens in {a.out} are up to date")
        return 0
    for path in make_all(a.out, names, sensor=not a.paper):
        print(f"{os.path.getsize(path):8d}  {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
