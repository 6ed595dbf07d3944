"""Evaluate a weight file on a vtloc-synth/1 dataset (docs/eval.md), the PyTorch
reference of ``vtloc eval``.

  python3 -m weights_tools.eval --model M.safetensors --data DIR [--split test|train|all]
      [--objects all|known|unknown] [--iters N] [--topk K] [--json FILE]
      [--mm-per-px MM]

Frames are rescaled to the model's sensor pixel size (``tactile.rescale``) when the
model's config and the dataset's index.json both record one and they differ, or to
``--mm-per-px`` (the frames' pixel size) when given.

Each object's cloud is encoded once (normalised frame of SPEC 1); its touches run in
batches.  Several touches (SPEC 6) are evaluated by ``vtloc eval --sequence``: the
multi-touch filter lives in the engine only (engine/track), its ops checked against
their C++ references.
"""

import argparse
import json
import os
import sys
import time

import numpy as np
import torch

from . import metrics, post
from . import model as model_mod
from .dataset import DatasetError, read_dataset
from .tactile import check_mm_per_px, preprocess, sensor_rescale

SPLIT_TOUCHES = {"test": ("test",), "train": ("train",), "all": ("train", "test")}
OBJECT_FILTER = {"all": ("seen", "unseen"), "known": ("seen",), "unknown": ("unseen",)}


def network_cloud(model, points):
    """Object cloud (N x 6, mm) -> (network input 1 x N x 6|3, centre, scale)."""
    cloud, centre, scale = post.normalise_cloud(torch.as_tensor(points))
    if not model.cfg["point"]["use_normals"]:
        cloud = cloud[:, :3]
    return cloud[None].contiguous(), centre, scale


@torch.no_grad()
def predict(model, obj, touches, iters=None, batch=32, images=None, mm_per_px=None):
    """c^p in object units (len(touches) x 3, float64) for touches of one object.
    ``images``: optional touch id -> uint8 frame (else read from disk);
    ``mm_per_px``: the frames' pixel size, rescaled to the model's sensor."""
    cfg = model.cfg["tactile"]
    cloud, centre, scale = network_cloud(model, obj.points)
    fp = model.point(cloud)
    out = []
    for i in range(0, len(touches), batch):
        chunk = touches[i:i + batch]
        x = torch.cat([preprocess(sensor_rescale(images[t.id] if images is not None else obj.image(t),
                                                 model.cfg, mm_per_px),
                                  cfg["crop"], cfg["in_size"]) for t in chunk])
        ft = model.tactile(x)
        cp, _ = model.contact(ft, fp.expand(len(chunk), -1), iters)
        out.append(cp.double() * scale + centre)
    return torch.cat(out).numpy() if out else np.zeros((0, 3))


def collection_path(obj):
    """Train and test touches in collection order (``order`` >= 0)."""
    return sorted((t for t in obj.touches if t.order >= 0), key=lambda t: t.order)


def frame_mm_per_px(model_cfg, ds_sensor, override=None):
    """The pixel size to rescale a dataset's frames from, or None (no rescale):
    ``override`` when given, else the dataset's sensor.mm_per_px when the model's
    config records a different one."""
    model_sensor = model_cfg.get("sensor")
    if override is not None:
        override = check_mm_per_px(override, "--mm-per-px")
        return None if model_sensor is not None and override == model_sensor["mm_per_px"] else override
    data_mm = (ds_sensor or {}).get("mm_per_px")
    if model_sensor is None or data_mm is None or float(data_mm) == model_sensor["mm_per_px"]:
        return None
    return check_mm_per_px(float(data_mm), "the dataset's sensor.mm_per_px")


def evaluate(model, ds, split="test", objects="all", iters=None, topk=5,
             batch=32, progress=None, mm_per_px=None):
    """Returns (rows, per_touch, seconds of network time, touches run)."""
    per_touch, net_s, net_n = [], 0.0, 0
    subsets = {}
    for obj in ds.objects:
        if obj.object_split not in OBJECT_FILTER[objects]:
            continue
        chosen = obj.touches_of(*SPLIT_TOUCHES[split])
        if not chosen:
            continue
        if obj.candidates.shape[0] == 0:
            raise DatasetError(f"{obj.folder}/touches.csv: no test touches, so no candidates")
        subsets[obj.name] = obj.subset
        frame = metrics.ObjectFrame(obj.points, obj.candidates)
        run = sorted(chosen, key=lambda t: t.id)
        t0 = time.perf_counter()
        preds = predict(model, obj, run, iters, batch, mm_per_px=mm_per_px)
        net_s += time.perf_counter() - t0
        net_n += len(run)
        pred = {t.id: p for t, p in zip(run, preds)}
        for t in chosen:
            c = pred[t.id]
            m = metrics.touch_metrics(frame, c, t.contact, topk)
            per_touch.append({"object": obj.name, "touch": t.id, "subset": obj.subset, **m,
                              "contact": [float(v) for v in c]})
        if progress is not None:
            progress(obj.name, len(chosen))
    rows = metrics.aggregate(per_touch, subsets, model.cfg["name"])
    return rows, per_touch, net_s, net_n


def format_table(rows):
    def f(v, fmt):
        return "-" if v is None else format(v, fmt)
    lines = [f"{'method':<16} {'subset':<12} {'objects':>7} {'touches':>7} {'mm':>7} "
             f"{'ND %':>6} {'Top-1':>6} {'Top-5':>6} {'MPE':>6}"]
    for r in rows:
        lines.append(f"{r['method']:<16} {r['subset']:<12} {r['objects']:>7} {r['touches']:>7} "
                     f"{f(r['mm'], '7.2f')} {f(r['nd'], '6.2f')} {f(r['top1'], '6.1f')} "
                     f"{f(r['top5'], '6.1f')} {f(r['mpe'], '6.3f')}")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m weights_tools.eval", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True, help="weight file (.safetensors)")
    ap.add_argument("--data", required=True, help="dataset folder (docs/dataset.md)")
    ap.add_argument("--split", choices=tuple(SPLIT_TOUCHES), default="test")
    ap.add_argument("--objects", choices=tuple(OBJECT_FILTER), default="all")
    ap.add_argument("--iters", type=int, help="ILU iterations (default: the config's)")
    ap.add_argument("--topk", type=int, default=5)
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--threads", type=int, default=0, help="torch threads (0: all cores)")
    ap.add_argument("--json", help="write the vtloc-eval/1 report here")
    ap.add_argument("--mm-per-px", type=float, metavar="MM",
                    help="the frames' pixel size (default: the dataset's, when the model's differs)")
    args = ap.parse_args(argv)
    if args.topk < 1 or args.batch < 1:
        ap.error("--topk and --batch must be >= 1")
    torch.set_num_threads(args.threads or os.cpu_count() or 1)
    try:
        model = model_mod.load(args.model).eval()
        ds = read_dataset(args.data)
        mm_per_px = frame_mm_per_px(model.cfg, ds.sensor, args.mm_per_px)
        if args.mm_per_px is not None and model.cfg.get("sensor") is None:
            raise ValueError(f"{args.model} has no sensor pixel size in its config; cannot rescale")
        if mm_per_px is not None:
            print(f"rescaling frames from {mm_per_px:g} to {model.cfg['sensor']['mm_per_px']:g} mm per pixel",
                  file=sys.stderr)
        rows, per_touch, net_s, net_n = evaluate(
            model, ds, args.split, args.objects, args.iters, args.topk,
            args.batch, mm_per_px=mm_per_px)
    except (DatasetError, ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    iters = None
    if model.cfg["head"] == "ilu":
        iters = model.cfg["ilu"]["iters"] if args.iters is None else args.iters
    report = {
        "format": "vtloc-eval/1", "model": args.model, "config": model.cfg["name"],
        "data": args.data, "split": args.split, "objects": args.objects, "iters": iters,
        "topk": args.topk, "sequence": 1, "mm_per_px": mm_per_px,
        "rows": rows, "per_touch": per_touch,
        "time_per_touch_ms": 1000.0 * net_s / net_n if net_n else None,
    }
    print(format_table(rows))
    if report["time_per_touch_ms"] is not None:
        print(f"{net_n} touches through the network, {report['time_per_touch_ms']:.2f} ms each")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=1)
            f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
