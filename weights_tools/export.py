"""Write a weight file: random weights for a config, or a trained checkpoint.

  python3 -m weights_tools.export --config vtloc-tiny --seed 0 -o out.safetensors
  python3 -m weights_tools.export --config vtloc-r18 --checkpoint ckpt.pt \
      --rename module.= --rename net.backbone.=tactile.backbone. -o out.safetensors
"""

import argparse
import json
import math
import sys

import torch
from torch import nn

from . import config as config_mod
from . import model as model_mod
from . import post, synthetic
from .tactile import preprocess

# Calibration inputs for the BatchNorm statistics (fixed: independent of --seed).
CALIB_SEEDS = (1, 2)


def _final_linears(model):
    """Names of layers whose output is not followed by a ReLU-like activation."""
    names = set()
    for name, mod in model.named_modules():
        if isinstance(mod, nn.Sequential):
            last = [n for n, m in mod.named_children() if isinstance(m, nn.Linear)]
            if last and last[-1] == str(len(mod) - 1):
                names.add(f"{name}.{last[-1]}")
    return names


def init_random(model, gen):
    """He-style init (std gain / sqrt(fan_in)) so activations stay O(1);
    BatchNorm affine parameters randomised.  Draws in module order from ``gen``."""
    final = _final_linears(model)
    with torch.no_grad():
        for name, mod in model.named_modules():
            if isinstance(mod, (nn.Conv2d, nn.Linear)):
                gain = 1.0 if name in final or name.startswith("ilu.conv") else math.sqrt(2)
                if name == "ilu.head.2":
                    # small steps that add up to |c_N| = O(1) after the default iterations
                    gain = 2.5 / max(model.cfg["ilu"]["iters"], 1)
                elif name in final and name.startswith("mcr."):
                    gain = 0.3  # keep tanh out of saturation
                fan_in = mod.weight[0].numel()
                mod.weight.normal_(0, gain / math.sqrt(fan_in), generator=gen)
                if mod.bias is not None:
                    mod.bias.normal_(0, 0.1 if name != "ilu.head.2" else 0.005, generator=gen)
            elif isinstance(mod, nn.BatchNorm2d):
                mod.weight.uniform_(0.5, 1.5, generator=gen)
                mod.bias.normal_(0, 0.2, generator=gen)
            elif name == "gma":
                mod.weight.normal_(0, math.sqrt(2.0 / mod.weight.shape[0]), generator=gen)


def calibration_inputs(cfg, dtype):
    t = cfg["tactile"]
    images = torch.cat([preprocess(synthetic.tactile_image(s), t["crop"], t["in_size"], dtype)
                        for s in CALIB_SEEDS])
    clouds = []
    for s in CALIB_SEEDS:
        cloud, _, _ = post.normalise_cloud(
            torch.from_numpy(synthetic.superellipsoid_cloud(s, cfg["point"]["n_points"])))
        clouds.append(cloud if cfg["point"]["use_normals"] else cloud[:, :3])
    return images, torch.stack(clouds).to(dtype)


def calibrate_batchnorm(model, gen):
    """Set every BatchNorm's running statistics from its actual eval-mode input
    on synthetic data, then perturb them (mean + 0.1 std N(0,1), var * U(0.5, 1.5))
    so that folding them is really exercised while activations stay O(1).
    A pre-hook sets each layer just before it runs, so one forward pass
    calibrates every layer given the already calibrated ones before it."""

    def hook(bn, args):
        x = args[0].detach().transpose(0, 1).reshape(bn.num_features, -1)
        mean, var = x.mean(dim=1), x.var(dim=1, unbiased=False)
        var = var.clamp_min(1e-2 * float(var.mean()) + 1e-12)  # no near-constant channel blow-up
        noise = torch.empty_like(mean).normal_(0, 1, generator=gen)
        bn.running_mean.copy_(mean + 0.1 * var.sqrt() * noise)
        bn.running_var.copy_(var * torch.empty_like(var).uniform_(0.5, 1.5, generator=gen))

    handles = [m.register_forward_pre_hook(hook) for m in model.modules()
               if isinstance(m, nn.BatchNorm2d)]
    try:
        images, clouds = calibration_inputs(model.cfg, next(model.parameters()).dtype)
        with torch.no_grad():
            model.eval()(images, clouds)
    finally:
        for h in handles:
            h.remove()


def random_model(cfg, seed, dtype=torch.float64):
    """A model with deterministic random weights.  Built and calibrated in
    float64 so the float32 weights do not depend on the machine's float32
    kernels; returned in float32.  dtype float32 calibrates 2-3x faster, for
    weights that are made and used on one machine (the paper-size goldens)."""
    model = model_mod.VTLoc(cfg).to(dtype)
    gen = torch.Generator().manual_seed(int(seed))
    init_random(model, gen)
    calibrate_batchnorm(model, gen)
    return model.float().eval()


def _state_from_checkpoint(path):
    obj = torch.load(path, map_location="cpu")
    if isinstance(obj, dict) and "state_dict" in obj and isinstance(obj["state_dict"], dict):
        obj = obj["state_dict"]
    if isinstance(obj, nn.Module):
        obj = obj.state_dict()
    if not isinstance(obj, dict) or not all(isinstance(v, torch.Tensor) for v in obj.values()):
        raise ValueError(f"{path}: expected a state_dict or {{'state_dict': ...}}")
    return obj


def rename_keys(state, renames=(), drops=()):
    """Apply prefix renames (first matching OLD wins) and drop prefixes."""
    out = {}
    for k, v in state.items():
        for old, new in renames:
            if k.startswith(old):
                k = new + k[len(old):]
                break
        if any(k.startswith(d) for d in drops):
            continue
        if k in out:
            raise ValueError(f"two checkpoint keys map to {k!r}")
        out[k] = v
    return out


def model_from_checkpoint(cfg, path, renames=(), drops=()):
    model = model_mod.VTLoc(cfg)
    state = rename_keys(_state_from_checkpoint(path), renames, drops)
    own = model.state_dict()
    missing = sorted(k for k in own if k not in state and not k.endswith("num_batches_tracked"))
    unexpected = sorted(k for k in state if k not in own)
    if missing or unexpected:
        raise ValueError("checkpoint does not match the config\n  missing: "
                         f"{missing[:20]}{' ...' if len(missing) > 20 else ''}\n  unexpected: "
                         f"{unexpected[:20]}{' ...' if len(unexpected) > 20 else ''}")
    bad = [k for k in state if state[k].shape != own[k].shape]
    if bad:
        raise ValueError("shape mismatch: " + ", ".join(
            f"{k} {tuple(state[k].shape)} vs {tuple(own[k].shape)}" for k in bad[:20]))
    return model_mod.load_state(model, state)


def _pair(text):
    if "=" not in text:
        raise argparse.ArgumentTypeError("expected OLD=NEW")
    return tuple(text.split("=", 1))


def load_config(name=None, json_path=None):
    if (name is None) == (json_path is None):
        raise ValueError("give exactly one of --config and --config-json")
    if name is not None:
        return config_mod.named(name)
    with open(json_path) as f:
        return config_mod.canonical(json.load(f))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m weights_tools.export", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", help=f"named config: {', '.join(sorted(config_mod.NAMED))}")
    ap.add_argument("--config-json", help="config as a JSON file (schema in README.md)")
    ap.add_argument("--seed", type=int, default=0, help="seed for random weights")
    ap.add_argument("--checkpoint", help="torch checkpoint: a state_dict or {'state_dict': ...}")
    ap.add_argument("--rename", type=_pair, action="append", default=[], metavar="OLD=NEW",
                    help="replace key prefix OLD by NEW (repeatable, first match wins)")
    ap.add_argument("--drop", action="append", default=[], metavar="PREFIX",
                    help="ignore checkpoint keys starting with PREFIX (after renaming)")
    ap.add_argument("--dtype", choices=("f32", "f16"), default="f32",
                    help="storage type of float tensors")
    ap.add_argument("-o", "--output", required=True)
    args = ap.parse_args(argv)
    try:
        cfg = load_config(args.config, args.config_json)
        if args.checkpoint:
            model = model_from_checkpoint(cfg, args.checkpoint, args.rename, args.drop)
        else:
            model = random_model(cfg, args.seed)
    except (ValueError, KeyError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    dtype = torch.float16 if args.dtype == "f16" else torch.float32
    model_mod.save(model, args.output, dtype)
    n = sum(p.numel() for p in model.state_dict().values())
    print(f"wrote {args.output}: {cfg['name']}, {n} values")
    return 0


if __name__ == "__main__":
    sys.exit(main())
