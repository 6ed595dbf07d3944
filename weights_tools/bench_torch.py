"""The PyTorch reference timed on the engine's inputs, for vtloc-bench --vs-pytorch.

  python3 -m weights_tools.bench_torch --weights W.safetensors --tactile IMG --cloud CLOUD.ply
      [--reps 20] [--warmup 3] [--threads N] [--device cpu|cuda] [--json OUT]

float32, eval mode, no autograd, ``--threads`` intra-op threads (default: all cores).
``--device cuda``: the model and the cloud on the GPU (the image decoded and cropped on
the CPU, as the engine's is uploaded, then moved there inside the preprocess stage);
each timed run ends with torch.cuda.synchronize(), so it counts the GPU's work.
cuDNN's autotuner is left off (PyTorch's default): one touch at a time, as deployed.
One touch end to end: preprocessing, cloud normalisation, tactile and point encoders
(FPS and ball query included), GMA, the contact head, top-K and heat-map over the
cloud's points; and each of those stages alone (the stage names of vtloc-bench).
Medians over --reps runs after --warmup untimed ones.  Prints JSON (or writes it).
"""

import argparse
import json
import os
import re
import statistics
import sys
import time

import torch

from . import model as model_mod
from . import post
from .inputs import read_cloud, read_tactile
from .tactile import preprocess


def blas_of_torch():
    """What torch says it was built with for BLAS, and the library it loaded."""
    cfg = torch.__config__.show()
    m = re.search(r"BLAS_INFO=([^,\n]+)", cfg)
    built = m.group(1).strip() if m else "unknown"
    loaded = "unknown"
    try:
        with open("/proc/self/maps") as f:
            libs = {os.path.basename(l.split()[-1]) for l in f if "blas" in l.lower() or "mkl" in l.lower()}
        loaded = ", ".join(sorted(libs)) or "none mapped"
    except OSError:
        pass
    return {"built_with": built, "loaded": loaded}


def timed(fn, reps, warmup, sync=lambda: None):
    for _ in range(warmup):
        fn()
    sync()
    out = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        sync()
        out.append(1000.0 * (time.perf_counter() - t0))
    return {"median": statistics.median(out), "min": min(out), "n": len(out)}


def run(args):
    torch.set_num_threads(args.threads or os.cpu_count() or 1)
    if args.device == "cuda" and not torch.cuda.is_available():
        raise ValueError("--device cuda: this torch sees no CUDA GPU")
    dev = torch.device(args.device)
    sync = torch.cuda.synchronize if dev.type == "cuda" else (lambda: None)
    net = model_mod.load(args.weights).float().eval().to(dev)
    cfg = net.cfg
    image = torch.as_tensor(read_tactile(args.tactile))
    cloud = torch.as_tensor(read_cloud(args.cloud)).float().to(dev)
    t = cfg["tactile"]
    k = cfg["K"]

    def prep():
        return preprocess(image, t["crop"], t["in_size"]).to(dev)  # 1 x 3 x S x S

    def point_in():
        c, _, _ = post.normalise_cloud(cloud)
        return (c if cfg["point"]["use_normals"] else c[:, :3].contiguous())[None]

    x, pc = prep(), point_in()
    with torch.no_grad():
        ft, fp = net.tactile(x), net.point(pc)
        cp, _ = net.contact(ft, fp)

    def heads():
        if net.has("gma"):
            net.gma(torch.cat([ft, fp], dim=-1))
        return net.contact(ft, fp)[0]

    def retrieval():
        order, _ = post.top_k(cp[0], pc[0, :, :3], k)
        post.heatmap(pc[0, :, :3], pc[0, order, :3])

    def whole():
        xi, pci = prep(), point_in()
        f_t, f_p = net.tactile(xi), net.point(pci)
        if net.has("gma"):
            net.gma(torch.cat([f_t, f_p], dim=-1))
        c, _ = net.contact(f_t, f_p)
        order, _ = post.top_k(c[0], pci[0, :, :3], k)
        post.heatmap(pci[0, :, :3], pci[0, order, :3])

    with torch.no_grad():
        stages = {
            "preprocess": timed(prep, args.reps, args.warmup, sync),
            "tactile": timed(lambda: net.tactile(x), args.reps, args.warmup, sync),
            "point": timed(lambda: net.point(point_in()), args.reps, args.warmup, sync),
            "heads": timed(heads, args.reps, args.warmup, sync),
            "retrieval": timed(retrieval, args.reps, args.warmup, sync),
        }
        e2e = timed(whole, args.reps, args.warmup, sync)
    where = torch.cuda.get_device_name(dev) if dev.type == "cuda" else "cpu"
    return {"tool": "weights_tools.bench_torch", "torch": torch.__version__, "dtype": "float32", "device": where,
            "threads": torch.get_num_threads(), "blas": blas_of_torch(), "config": cfg["name"],
            "points": int(cloud.shape[0]), "reps": args.reps, "warmup": args.warmup,
            "end_to_end_ms": e2e, "stages_ms": stages}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m weights_tools.bench_torch", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", required=True)
    ap.add_argument("--tactile", required=True)
    ap.add_argument("--cloud", required=True, help="PLY with x y z nx ny nz (object units)")
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--warmup", type=int, default=3)
    ap.add_argument("--threads", type=int, default=0, help="0: all cores")
    ap.add_argument("--device", choices=["cpu", "cuda"], default="cpu")
    ap.add_argument("--json", help="write here instead of stdout")
    args = ap.parse_args(argv)
    if args.reps < 1 or args.warmup < 0:
        ap.error("--reps >= 1 and --warmup >= 0")
    try:
        rep = run(args)
    except (OSError, ValueError, KeyError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    text = json.dumps(rep, indent=2)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text + "\n")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
