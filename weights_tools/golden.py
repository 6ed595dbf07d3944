"""Golden file: every intermediate of one run, named as in SPEC 8.

  python3 -m weights_tools.golden --weights W.safetensors \
      (--tactile img.png | --synthetic-tactile SEED) \
      (--cloud cloud.ply | --synthetic-cloud SEED) \
      [--candidates pts.txt] [--iters N] [--K K] [--symmetry px,py,pz,dx,dy,dz,M] \
      [--mm-per-px MM] -o golden.safetensors

--mm-per-px: the frame's pixel size; it is rescaled to the config's
sensor.mm_per_px before the crop (``tactile.rescale``); the rescaled frame
is written as ``tactile.rescaled``.

The network runs in float64 (``--dtype``) on float32-rounded stage inputs and
every float result is rounded to float32: the golden is then (nearly) the exact
answer and does not depend on this machine's float32 kernels.  FPS, ball query
and top-K scores are computed in float32 exactly as SPEC 2/3 define them.
"""

import argparse
import copy
import hashlib
import json
import sys

import torch

from . import model as model_mod
from . import post, safetensors_io, synthetic
from .inputs import read_candidates, read_cloud, read_tactile
from .tactile import preprocess, sensor_rescale


def run(model, image_u8, cloud, candidates=None, iters=None, k=None, symmetry=None,
        dtype=torch.float64, mm_per_px=None):
    """One object, one touch.  image_u8: H x W x 3 uint8; cloud: N x 6 object
    units; candidates: M x 3 object units (default: the cloud's points);
    symmetry: (axis point xyz, axis direction xyz, order M) in object units.
    mm_per_px: the frame's pixel size (rescaled to the config's sensor).
    Returns {name: tensor} with SPEC 8 names plus the raw inputs."""
    cfg = model.cfg
    net = copy.deepcopy(model).to(dtype).eval()
    image_u8 = torch.as_tensor(image_u8)
    cloud = torch.as_tensor(cloud).float()
    if cloud.dim() != 2 or cloud.shape[1] != 6:
        raise ValueError("cloud must be N x 6 (xyz, normals)")
    cands = cloud[:, :3] if candidates is None else torch.as_tensor(candidates).float()
    k = cfg["K"] if k is None else int(k)
    out = {"input.tactile": image_u8, "input.cloud": cloud, "input.candidates": cands}

    t = cfg["tactile"]
    frame = sensor_rescale(image_u8, cfg, mm_per_px)
    if mm_per_px is not None:
        out["tactile.rescaled"] = frame
    x = preprocess(frame, t["crop"], t["in_size"], torch.float64).float()
    cloud_n, centre, scale = post.normalise_cloud(cloud)
    net_cloud = cloud_n if cfg["point"]["use_normals"] else cloud_n[:, :3].contiguous()
    out.update({"tactile.input": x, "point.cloud": net_cloud,
                "point.centre": centre.float(), "point.scale": scale.float()})

    trace = {}
    with torch.no_grad():
        # stage outputs are rounded to float32 before the next stage consumes them,
        # exactly as an engine comparing stage by stage would see them
        ft = net.tactile(x.to(dtype)).float()
        fp = net.point(net_cloud[None].to(dtype), trace=trace).float()
        out["tactile.feature"], out["point.feature"] = ft[0], fp[0]
        for name, idx in trace.items():
            out[name] = idx[0].int()
        if net.has("gma"):
            pd = net.gma(torch.cat([ft, fp], dim=-1).to(dtype)).float()[0]
            out["gma.cloud"] = pd
            out["gma.chamfer"] = post.chamfer(pd, cloud_n).float()  # shape [], 6-wide
        cp, cs = net.contact(ft.to(dtype), fp.to(dtype), iters)
    if cs is not None:
        out["ilu.c"] = cs[0].float()
    contact = cp[0].float()
    out["contact"] = contact
    out["contact.object"] = (contact.double() * scale + centre).float()

    cands_n = post.normalise_points(cands, centre, scale)
    index, score = post.top_k(contact, cands_n, k)
    out["topk.index"], out["topk.score"] = index.int(), score
    sym = None
    if symmetry is not None:
        point, direction, order = symmetry
        sym = (post.normalise_points(torch.tensor([point]), centre, scale)[0].double(),
               torch.tensor(direction, dtype=torch.float64), int(order))
    out["heatmap"] = post.heatmap(cloud_n[:, :3], cands_n[index], symmetry=sym)
    return out


def _symmetry(text):
    v = text.split(",")
    if len(v) != 7:
        raise argparse.ArgumentTypeError("expected px,py,pz,dx,dy,dz,M")
    point, direction, order = [float(a) for a in v[:3]], [float(a) for a in v[3:6]], int(v[6])
    if order < 1 or not any(direction):
        raise argparse.ArgumentTypeError("need M >= 1 and a non-zero direction")
    return point, direction, order


def write(path, tensors, cfg, extra_meta):
    meta = model_mod.config_metadata(cfg)
    meta.update({f"vtloc.golden.{k}": v for k, v in extra_meta.items()})
    safetensors_io.save(path, tensors, meta)


def make(weights, tactile=None, synthetic_tactile=None, cloud=None, synthetic_cloud=None,
         candidates=None, iters=None, k=None, symmetry=None, dtype=torch.float64,
         mm_per_px=None):
    """Load inputs, run, return (tensors, metadata extras, config)."""
    model = model_mod.load(weights)
    if mm_per_px is not None and model.cfg.get("sensor") is None:
        raise ValueError(f"{weights} has no sensor pixel size in its config; cannot rescale")
    cfg = model.cfg
    if (tactile is None) == (synthetic_tactile is None):
        raise ValueError("give exactly one of --tactile and --synthetic-tactile")
    if (cloud is None) == (synthetic_cloud is None):
        raise ValueError("give exactly one of --cloud and --synthetic-cloud")
    if tactile is not None:
        image, image_src = read_tactile(tactile), f"file:{tactile}"
    else:
        image, image_src = synthetic.tactile_image(synthetic_tactile), \
            f"synthetic:{synthetic_tactile}"
    if cloud is not None:
        pts, cloud_src = read_cloud(cloud), f"file:{cloud}"
    else:
        pts = torch.from_numpy(synthetic.superellipsoid_cloud(synthetic_cloud,
                                                              cfg["point"]["n_points"]))
        cloud_src = f"synthetic:{synthetic_cloud}"
    cands = None if candidates is None else read_candidates(candidates)
    tensors = run(model, image, pts, cands, iters, k, symmetry, dtype, mm_per_px)
    with open(weights, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    n_iters = tensors["ilu.c"].shape[0] if "ilu.c" in tensors else 0
    meta = {"weights_sha256": digest, "tactile": image_src, "cloud": cloud_src,
            "candidates": "cloud" if candidates is None else f"file:{candidates}",
            "iters": str(n_iters), "K": str(tensors["topk.index"].numel()),
            "symmetry": json.dumps(symmetry) if symmetry else "",
            "compute_dtype": str(dtype).replace("torch.", "")}
    if mm_per_px is not None:
        meta["mm_per_px"] = repr(float(mm_per_px))
    return tensors, meta, cfg


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m weights_tools.golden", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", required=True)
    ap.add_argument("--tactile", help="tactile image (PNG/JPEG, RGB)")
    ap.add_argument("--synthetic-tactile", type=int, metavar="SEED")
    ap.add_argument("--cloud", help="point cloud (.ply with normals, .npy or text N x 6)")
    ap.add_argument("--synthetic-cloud", type=int, metavar="SEED")
    ap.add_argument("--candidates", help="candidate contacts, object units (.ply/.npy/text)")
    ap.add_argument("--iters", type=int, help="ILU iterations (default: the config's)")
    ap.add_argument("--K", type=int, dest="k", help="top-K size (default: the config's)")
    ap.add_argument("--symmetry", type=_symmetry, metavar="px,py,pz,dx,dy,dz,M",
                    help="rotational symmetry prior (axis point in object units)")
    ap.add_argument("--mm-per-px", type=float, metavar="MM",
                    help="the frame's pixel size in mm; rescaled to the config's sensor.mm_per_px")
    ap.add_argument("--dtype", choices=("float64", "float32"), default="float64",
                    help="precision the network runs in")
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args(argv)
    try:
        tensors, meta, cfg = make(a.weights, a.tactile, a.synthetic_tactile, a.cloud,
                                  a.synthetic_cloud, a.candidates, a.iters, a.k, a.symmetry,
                                  getattr(torch, a.dtype), a.mm_per_px)
    except (ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    write(a.output, tensors, cfg, meta)
    print(f"wrote {a.output}: {len(tensors)} tensors, contact {tensors['contact'].tolist()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
