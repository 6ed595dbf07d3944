"""Train a VTLoc config on a vtloc-synth/1 dataset and export the weight file.

  python3 -m weights_tools.train --config vtloc-lite --data DIR --out RUN_DIR
      [--minutes M] [--steps S] [--seed 0] [--batch 16] [--lambda 1.0] [--resume]
      [--export-only]

Trains on the ``train`` and ``extra`` touches of the ``seen`` objects; a fixed share of
each seen object's ``train`` contacts is held out for validation (test touches are never
read).  A batch holds touches of one object, so the point encoder runs once per batch.
Writes RUN_DIR/checkpoint.pt (atomically, every few minutes), RUN_DIR/log.csv and at the
end RUN_DIR/model.safetensors with ``vtloc.provenance`` metadata.  See README "Training".
"""

import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time
import zlib

import numpy as np
import torch
import torch.nn.functional as F

from . import config as config_mod
from . import model as model_mod
from . import post, safetensors_io
from .dataset import DatasetError, read_dataset
from .pointnet2 import gather, run_stack
from .tactile import IMAGENET_MEAN, IMAGENET_STD, center_crop, crop_start

VAL_FRACTION = 0.1      # share of each seen object's train contacts held out
EXTRA_CLEARANCE_MM = 2.0  # extra renders this close to a held-out contact are dropped too
GAMMA = 0.9             # SPEC 4 sequence-loss decay
LOG_COLUMNS = ("step", "elapsed_s", "lr", "loss", "loss_seq", "loss_recon", "val_loss", "val_nd",
               "loss_aux")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


# ---------------------------------------------------------------- data

class TrainObject:
    """One seen object in memory: network cloud, Chamfer target, frames as uint8."""

    def __init__(self, model, obj, train_ids, val_ids):
        self.name, self.subset = obj.name, obj.subset
        cloud, self.centre, self.scale = post.normalise_cloud(torch.from_numpy(obj.points))
        self.target = cloud.clone()                 # normalised xyz + normals (SPEC 4 recon)
        self.cloud = (cloud if model.cfg["point"]["use_normals"] else cloud[:, :3])[None].contiguous()
        self.D = float(np.sqrt(((obj.points[:, None, :3] - obj.points[None, :, :3]) ** 2).sum(-1).max()))
        self.plan = sampling_plan(model, self.cloud)
        by_id = {t.id: t for t in obj.touches}
        self.ids = list(train_ids) + list(val_ids)
        self.n_train = len(train_ids)
        frames = [obj.image(by_id[i]) for i in self.ids]
        if len({f.shape for f in frames}) > 1:
            raise DatasetError(f"{obj.folder}: frames of different sizes")
        self.images = torch.from_numpy(np.stack(frames)) if frames else torch.zeros(0, 1, 1, 3, dtype=torch.uint8)
        self.contacts = post.normalise_points(
            np.stack([by_id[i].contact for i in self.ids]), self.centre, self.scale) \
            if self.ids else torch.zeros(0, 3)

    @property
    def train_index(self):
        return list(range(self.n_train))

    @property
    def val_index(self):
        return list(range(self.n_train, len(self.ids)))


def split_contacts(obj, fraction=VAL_FRACTION):
    """(training ids, validation ids) of a seen object: a fixed share of its train
    touches (chosen by the object's name, not by --seed, so every run validates on the
    same contacts) plus its extra touches not within EXTRA_CLEARANCE_MM of those."""
    train = [t for t in obj.touches if t.split == "train"]
    n_val = int(round(fraction * len(train)))
    rng = np.random.default_rng(zlib.crc32(obj.name.encode()))
    val = sorted(rng.choice(len(train), size=n_val, replace=False).tolist()) if n_val else []
    val_ids = [train[i].id for i in val]
    held = np.array([train[i].contact for i in val]).reshape(-1, 3)
    ids = [t.id for t in train if t.id not in set(val_ids)]
    for t in obj.touches:
        if t.split == "extra" and (not len(held) or np.linalg.norm(held - t.contact, axis=1).min()
                                    > EXTRA_CLEARANCE_MM):
            ids.append(t.id)
    return ids, val_ids


def load_objects(model, ds, fraction=VAL_FRACTION):
    out = []
    for obj in ds.objects:
        if obj.object_split != "seen":
            continue
        tr, va = split_contacts(obj, fraction)
        if tr:
            out.append(TrainObject(model, obj, tr, va))
    if not out:
        raise DatasetError(f"{ds.root}/dataset.json: no seen object with training touches")
    return out


# ---------------------------------------------------------------- network pieces

@torch.no_grad()
def sampling_plan(model, cloud):
    """FPS and ball-query indices of every SA stage.  They depend only on the cloud
    (never on weights), and the cloud is not augmented, so they are computed once."""
    trace = {}
    was = model.training
    model.point.eval()(cloud, trace=trace)
    model.point.train(was)
    n = model.point.n_stages
    return [(trace[f"point.sa{i}.fps"],
             [trace[f"point.sa{i}.ball.{s}"] for s in range(len(getattr(model.point, f"sa{i}").radii))])
            for i in range(1, n + 1)]


def point_features(pe, cloud, plan, local=None):
    """PointEncoder.forward with precomputed sampling (same graph, same modules).
    ``local``, a list, receives (centres, features) of every SA stage but group-all."""
    xyz = cloud[..., :3]
    feats = cloud[..., 3:6] if pe.use_normals else None
    for i, (fps, balls) in enumerate(plan, start=1):
        sa = getattr(pe, f"sa{i}")
        new_xyz = gather(xyz, fps)
        outs = []
        for s, idx in enumerate(balls):
            rel = gather(xyz, idx) - new_xyz[:, :, None, :]
            grouped = rel if feats is None else torch.cat([gather(feats, idx), rel], dim=-1)
            x = run_stack(grouped.permute(0, 3, 2, 1), sa.conv_blocks[s], sa.bn_blocks[s])
            outs.append(x.max(dim=2).values)
        xyz, feats = new_xyz, torch.cat(outs, dim=1).transpose(1, 2)
        if local is not None:
            local.append((xyz, feats))
    return pe.mlp(getattr(pe, f"sa{len(plan) + 1}")(xyz, feats))


@torch.no_grad()
def calibrate_point_bn(model, objects):
    """Point-branch BatchNorm statistics over every training object at once.

    A step sees one object, so train-mode BatchNorm would normalise each cloud by its
    own statistics: the features that tell objects apart are removed in training and
    come back (through the running averages) at inference. Instead the point branch
    runs with frozen statistics, recomputed over all objects every few steps."""
    bns = [m for m in model.point.modules() if isinstance(m, torch.nn.BatchNorm2d)
           or isinstance(m, torch.nn.BatchNorm1d)]
    for m in bns:
        m.reset_running_stats()
        m.momentum = None  # cumulative average over the calibration forwards
        m.train()
    for o in objects:
        point_features(model.point, o.cloud, o.plan)
    for m in bns:
        m.momentum = 0.1
    model.point.eval()


def _normalise(x):
    mean = torch.tensor(IMAGENET_MEAN).view(1, 3, 1, 1)
    std = torch.tensor(IMAGENET_STD).view(1, 3, 1, 1)
    return (x - mean) / std


def rotated_crops(x, crop, size, angles):
    """Centre crop + bilinear resize of B x 3 x H x W images as tactile.preprocess does,
    but with each crop rotated by ``angles`` (radians) about the image centre, all in one
    grid_sample.  Rotated corners read reflected pixels; where the crop itself lies
    outside the image (crop > H or W) the result is zero, as in preprocess."""
    B, _, H, W = x.shape
    pos = (torch.arange(size, dtype=torch.float32) + 0.5) * (crop / size) - 0.5  # crop pixels
    ys = crop_start(H, crop) + pos - (H - 1) / 2   # relative to the image centre
    xs = crop_start(W, crop) + pos - (W - 1) / 2
    yy, xx = torch.meshgrid(ys, xs, indexing="ij")
    c, s = torch.cos(angles).view(B, 1, 1), torch.sin(angles).view(B, 1, 1)
    X = c * xx - s * yy + (W - 1) / 2
    Y = s * xx + c * yy + (H - 1) / 2
    grid = torch.stack([(2 * X + 1) / W - 1, (2 * Y + 1) / H - 1], dim=-1)
    out = F.grid_sample(x, grid, mode="bilinear", padding_mode="reflection", align_corners=False)
    inside = ((yy > -(H + 1) / 2) & (yy < (H + 1) / 2) & (xx > -(W + 1) / 2) & (xx < (W + 1) / 2))
    return out * inside.to(out.dtype)


def images_to_input(u8, cfg, gen=None, rotate=False):
    """B x H x W x 3 uint8 -> B x 3 x S x S network input: tactile.preprocess batched,
    with augmentation when ``gen`` is given.  The augmentations keep the label valid:
    a rotation about the image centre is a sensor spin (the contact is the centre's
    projection), and photometric jitter (gain, colour gain, offset, noise) changes no
    geometry.  No mirroring (that would be the imprint of a mirrored surface)."""
    x = u8.permute(0, 3, 1, 2).float() / 255.0
    t = cfg["tactile"]
    if gen is None:
        x = center_crop(x, t["crop"])
        if t["crop"] != t["in_size"]:
            x = F.interpolate(x, size=(t["in_size"], t["in_size"]), mode="bilinear",
                              align_corners=False, antialias=False)
        return _normalise(x)
    B = x.shape[0]
    # Rotation is off by default: the renders already have uniform spins, and random
    # rotations of the crop kept a 2-core-sized run from learning at all (measured:
    # one object, 600 steps, validation ND 45 % with rotation, 20 % without).
    angles = torch.rand(B, generator=gen) * (2 * math.pi) * (1.0 if rotate else 0.0)
    x = rotated_crops(x, t["crop"], t["in_size"], angles)
    gain = (0.8 + 0.4 * torch.rand(B, 1, 1, 1, generator=gen)) * \
           (0.9 + 0.2 * torch.rand(B, 3, 1, 1, generator=gen))
    offset = 0.1 * torch.rand(B, 1, 1, 1, generator=gen) - 0.05
    noise = 0.02 * torch.rand(B, 1, 1, 1, generator=gen) * torch.randn(x.shape, generator=gen)
    return _normalise((x * gain + offset + noise).clamp(0, 1))


def chamfer_batch(a, b):
    """SPEC 3 Chamfer of each a[i] (M x 6) against b (N x 6) -> B.  The nearest pairs
    are found without autograd and only they are differentiated: same value and
    gradient as differentiating the min over the whole B x M x N matrix, at a
    fraction of its cost."""
    with torch.no_grad():
        # ||a - b||^2 = |a|^2 + |b|^2 - 2 a.b; the norm constant along a search drops out,
        # and each search runs along contiguous rows (much faster than a strided argmin)
        B = a.shape[0]
        bt = b.t().expand(B, -1, -1)
        ja = torch.baddbmm((b * b).sum(-1).expand(B, 1, -1), a, bt, alpha=-2).argmin(dim=2)
        ib = torch.baddbmm((a * a).sum(-1)[:, None, :], b.expand(B, -1, -1), a.transpose(1, 2),
                           alpha=-2).argmin(dim=2)
    da = ((a - b[ja]) ** 2).sum(-1).mean(1)
    db = ((torch.gather(a, 1, ib[..., None].expand(-1, -1, a.shape[-1])) - b[None]) ** 2).sum(-1).mean(1)
    return da + db


class LocalMatch(torch.nn.Module):
    """Training-only auxiliary head, never exported: scores each centre of each of the
    point branch's SA stages against the tactile feature, with a soft target peaked at
    the centres nearest the true contact (width: half the stage's first ball radius).  With many objects the ILU loss alone gives
    the tactile branch almost no gradient (the same imprint lies at different places
    on different objects, so its average pull is towards the centre); this loss asks
    both encoders for local-shape features that agree, on every object alike."""

    def __init__(self, cfg, dim=32):
        super().__init__()
        sa = cfg["point"]["sa"]
        self.dim = dim
        self.q = torch.nn.ModuleList(torch.nn.Linear(cfg["C"], dim) for _ in sa)
        self.k = torch.nn.ModuleList(torch.nn.Linear(sum(m[-1] for m in st["mlps"]), dim) for st in sa)
        self.sigma = [0.5 * st["radii"][0] for st in sa]

    def forward(self, ft, local, gt):
        total = ft.new_zeros(())
        for q, k, sigma, (centres, feats) in zip(self.q, self.k, self.sigma, local):
            logits = q(ft) @ k(feats[0]).t() / math.sqrt(self.dim)
            d2 = ((gt[:, None, :] - centres[0][None]) ** 2).sum(-1)
            target = torch.softmax(-d2 / (2 * sigma ** 2), dim=1)
            total = total - (target * torch.log_softmax(logits, dim=1)).sum(1).mean()
        return total / len(self.q)


def feature_scale(f):
    """(RMS over channels - 1)^2, averaged over the batch."""
    return ((f.pow(2).mean(-1) + 1e-12).sqrt() - 1).pow(2).mean()


def losses(model, tobj, index, lam=1.0, gen=None, rotate=False, match=None, mu=0.0, beta=0.0):
    """Loss parts on touches ``index`` of one object: (total, seq, recon, c^p B x 3, aux).
    aux, the training-only terms (in the total, never in the exported graph): mu times
    the LocalMatch loss (with ``match``) plus beta times the feature-scale penalty, which
    keeps F^p and F^t near unit RMS.  Without it F^p grew to RMS ~10 (pushed by the
    Chamfer loss) and saturated the ILU's gates: its output stayed at the centre."""
    return group_losses(model, [(tobj, index)], lam, gen, rotate, match, mu, beta)


def group_losses(model, groups, lam=1.0, gen=None, rotate=False, match=None, mu=0.0, beta=0.0):
    """losses() over a batch made of groups (object, touch indices): one tactile forward
    over all frames (so its BatchNorm sees several objects, as running statistics do),
    the point branch once per group; per-object terms averaged over groups by size."""
    x = images_to_input(torch.cat([o.images[i] for o, i in groups]), model.cfg, gen, rotate)
    gt = torch.cat([o.contacts[i] for o, i in groups])
    B = len(gt)
    locals_, fps = [], []
    for o, i in groups:
        local = []
        fps.append(point_features(model.point, o.cloud, o.plan, local).expand(len(i), -1))
        locals_.append(local)
    fp = torch.cat(fps)
    ft = model.tactile(x)
    zero = ft.new_zeros(())
    starts = np.cumsum([0] + [len(i) for _, i in groups])
    parts = [slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:])]
    aux = zero
    if match is not None and mu > 0:
        aux = mu * sum(match(ft[p], loc, gt[p]) * (p.stop - p.start) for p, loc in zip(parts, locals_)) / B
    if beta > 0:
        aux = aux + beta * (sum(feature_scale(f[:1]) for f in fps) / len(fps) + feature_scale(ft))
    if model.cfg["head"] == "mcr":
        cp = model.mcr(torch.cat([ft, fp], dim=-1))
        seq = F.smooth_l1_loss(cp, gt)
    else:
        cs = model.ilu(ft, fp)
        n = cs.shape[1]
        if n == 0:
            cp, seq = ft.new_zeros(B, 3), zero
        else:
            w = GAMMA ** torch.arange(n - 1, -1, -1, dtype=cs.dtype)  # 0.9^(N-i), i = 1..N
            seq = (torch.linalg.vector_norm(cs - gt[:, None, :], dim=-1) * w).sum(1).mean()
            cp = cs[:, -1]
    recon = zero
    if model.has("gma"):
        cloud = model.gma(torch.cat([ft, fp], dim=-1))
        recon = sum(chamfer_batch(cloud[p], o.target).sum() for p, (o, _) in zip(parts, groups)) / B
    return seq + lam * recon + aux, seq, recon, cp, aux


@torch.no_grad()
def validate(model, objects, lam=1.0, batch=64):
    """(mean loss over validation touches, ND % averaged per object then over objects)."""
    was = model.training
    model.eval()
    tot, n, nds = 0.0, 0, []
    for o in objects:
        idx = o.val_index
        if not idx:
            continue
        errs = []
        for i in range(0, len(idx), batch):
            chunk = idx[i:i + batch]
            loss, _, _, cp, _ = losses(model, o, chunk, lam)
            tot += float(loss) * len(chunk)
            n += len(chunk)
            errs.append(torch.linalg.vector_norm(cp - o.contacts[chunk], dim=-1).double() * float(o.scale))
        nds.append(100.0 * float(torch.cat(errs).mean()) / o.D)
    model.train(was)
    if not n:
        return None, None
    return tot / n, float(np.mean(nds))


def validate_calibrated(model, objects, lam=1.0):
    """validate() with point-branch statistics of the current weights, leaving the
    training state (its statistics included) as it was, so that validating or
    checkpointing never changes what the run computes next."""
    saved = {k: v.clone() for k, v in model.point.state_dict().items()
             if k.endswith(("running_mean", "running_var", "num_batches_tracked"))}
    calibrate_point_bn(model, objects)
    val = validate(model, objects, lam)
    model.point.load_state_dict(saved, strict=False)
    model.point.eval()  # validate() restores train mode; the point branch trains with frozen statistics
    return val


# ---------------------------------------------------------------- sampling, schedule

class Sampler:
    """Epochs of batches made of ``groups`` chunks of batch/groups touches of one object
    each: every object's training touches shuffled and cut into chunks, all chunks
    shuffled, consecutive chunks batched.  Epoch e's order depends only on (seed, e), so
    the position (epoch, index) is all a checkpoint needs to continue identically."""

    def __init__(self, objects, batch, seed, groups=1):
        self.objects, self.batch, self.seed = objects, batch, seed
        self.groups = max(1, min(groups, batch))
        self.epoch, self.pos, self._batches = 0, 0, None

    def _make(self):
        g = np.random.default_rng([self.seed, self.epoch])
        size = self.batch // self.groups
        out = []
        for k, o in enumerate(self.objects):
            perm = g.permutation(o.n_train)
            for i in range(0, len(perm), size):
                chunk = perm[i:i + size]
                # a short remainder is a poor BatchNorm batch; its touches come back next epoch
                if len(chunk) >= max(1 if self.groups > 1 else 2, size // 2) or len(perm) < 2 * size:
                    out.append((k, chunk.tolist()))
        out = [out[i] for i in g.permutation(len(out))]
        return [out[i:i + self.groups] for i in range(0, len(out), self.groups)]

    def next(self):
        if self._batches is None:
            self._batches = self._make()
        if self.pos >= len(self._batches):
            self.epoch, self.pos = self.epoch + 1, 0
            self._batches = self._make()
        b = self._batches[self.pos]
        self.pos += 1
        return b

    def state(self):
        return {"epoch": self.epoch, "pos": self.pos}

    def load(self, st):
        self.epoch, self.pos, self._batches = st["epoch"], st["pos"], None


def learning_rate(base, step, progress, warmup=100, floor=0.02):
    """Linear warm-up, then cosine from ``base`` to ``floor * base`` over the budget."""
    w = min(1.0, (step + 1) / warmup)
    return base * w * (floor + (1 - floor) * 0.5 * (1 + math.cos(math.pi * min(progress, 1.0))))


# ---------------------------------------------------------------- files

def save_atomic(obj, path):
    tmp = path + ".tmp"
    torch.save(obj, tmp)
    os.replace(tmp, path)


def git_commit():
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True, timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                               capture_output=True, text=True, timeout=10)
        if head.returncode == 0:
            return head.stdout.strip(), bool(dirty.stdout.strip())
    except (OSError, subprocess.SubprocessError):
        pass
    return "unknown", None


def export_weights(model, path, provenance):
    """The reference's weight file (BatchNorm running statistics, eval semantics)
    plus ``vtloc.provenance`` metadata; written to a temporary name and renamed."""
    model = model.eval()
    sd = {k: (v.detach().float() if v.is_floating_point() else v) for k, v in model.state_dict().items()}
    meta = dict(model_mod.config_metadata(model.cfg))
    meta["vtloc.provenance"] = json.dumps(provenance, separators=(",", ":"))
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(safetensors_io.dumps(sd, meta))
    os.replace(tmp, path)


class Log:
    def __init__(self, path, resume_step=None):
        self.path = path
        rows = []
        if resume_step is not None and os.path.exists(path):
            with open(path, newline="") as f:
                rows = [r for r in csv.DictReader(f) if int(r["step"]) <= resume_step]
        with open(path, "w", newline="") as f:  # drop rows written after the checkpoint
            w = csv.DictWriter(f, LOG_COLUMNS)
            w.writeheader()
            w.writerows(rows)

    def write(self, **row):
        with open(self.path, "a", newline="") as f:
            csv.DictWriter(f, LOG_COLUMNS).writerow(
                {k: ("" if row.get(k) is None else (f"{row[k]:.6g}" if isinstance(row[k], float) else row[k]))
                 for k in LOG_COLUMNS})


# ---------------------------------------------------------------- main loop

def make_model(cfg, seed):
    torch.manual_seed(seed)
    model = model_mod.VTLoc(cfg).train()
    if model.has("ilu"):
        with torch.no_grad():  # small first steps: c_N starts near 0, inside the unit ball
            model.ilu.head[2].weight.mul_(0.1)
            model.ilu.head[2].bias.zero_()
    return model


def provenance(args, ds, objects, step, elapsed, val):
    commit, dirty = git_commit()
    used = {o.name: o for o in objects}
    return {
        "tool": "weights_tools.train", "config": args.config, "data": os.path.abspath(args.data),
        "data_format": "vtloc-synth/1", "data_seed": ds.seed, "sensor": ds.sensor,
        "objects": [{"name": o.name, "object_split": o.object_split, "subset": o.subset,
                     "train_touches": used[o.name].n_train if o.name in used else 0,
                     "val_touches": len(used[o.name].val_index) if o.name in used else 0}
                    for o in ds.objects],
        "steps": step, "wall_time_s": round(elapsed, 1), "seed": args.seed, "batch": args.batch,
        "lambda": args.lam, "objects_per_batch": args.groups, "match_weight": args.match, "feature_scale_weight": args.feature_scale, "lr": args.lr, "val_fraction": args.val_fraction, "rotate": args.rotate,
        "val_loss": val[0], "val_nd": val[1], "git_commit": commit, "git_dirty": dirty,
        # the command that started the run (a resume or --export-only keeps it), then this one
        "command": " ".join([os.path.basename(sys.executable), "-m", "weights_tools.train"] + args.first_argv),
        "last_command": " ".join([os.path.basename(sys.executable), "-m", "weights_tools.train"] + args.argv),
        "torch": torch.__version__,
    }


def run(args):
    os.makedirs(args.out, exist_ok=True)
    ckpt_path = os.path.join(args.out, "checkpoint.pt")
    ckpt = None
    if os.path.exists(ckpt_path):
        if not (args.resume or args.export_only):
            raise ValueError(f"{ckpt_path}: exists; pass --resume to continue it or use another --out")
        ckpt = torch.load(ckpt_path, map_location="cpu")
        saved = ckpt["args"]
        if saved["config"] != args.config and args.config is not None:
            raise ValueError(f"{ckpt_path}: trained config {saved['config']}, not {args.config}")
        for k in ("config", "seed", "batch", "lam", "lr", "minutes", "steps", "val_fraction", "rotate"):
            setattr(args, k, saved.get(k, getattr(args, k)))  # same run, same budget
        args.match = saved.get("match", 0.0)  # runs from before the auxiliary losses had none
        args.feature_scale = saved.get("feature_scale", 0.0)
        args.groups = saved.get("groups", 1)
        args.first_argv = saved.get("first_argv", args.argv)
    elif args.export_only:
        raise ValueError(f"{ckpt_path}: missing (nothing to export)")
    if args.config is None:
        raise ValueError("--config is required")
    cfg = config_mod.named(args.config)
    torch.set_num_threads(args.threads or os.cpu_count() or 1)
    ds = read_dataset(args.data)
    model = make_model(cfg, args.seed)
    objects = load_objects(model, ds, args.val_fraction)
    match = LocalMatch(cfg) if args.match > 0 else None  # seeded by make_model's manual_seed
    params = [p for p in model.parameters() if p.requires_grad]
    n_model = sum(p.numel() for p in params)
    if match is not None:
        params += list(match.parameters())
    opt = torch.optim.AdamW(params, lr=args.lr, weight_decay=1e-4)
    sampler = Sampler(objects, args.batch, args.seed, args.groups)
    gen = torch.Generator().manual_seed(args.seed)
    step, elapsed = 0, 0.0
    if ckpt is not None:
        model.load_state_dict(ckpt["state_dict"])
        if match is not None:
            match.load_state_dict(ckpt["match"])
        opt.load_state_dict(ckpt["optimizer"])
        step, elapsed = ckpt["step"], ckpt["elapsed_s"]
        sampler.load(ckpt["sampler"])
        gen.set_state(ckpt["aug_rng"])
        torch.set_rng_state(ckpt["torch_rng"])
    budget_s = None if args.minutes is None else 60.0 * args.minutes
    n_img = sum(o.images.numel() for o in objects)
    print(f"{cfg['name']}: {n_model} parameters; {len(objects)} objects, "
          f"{sum(o.n_train for o in objects)} training / {sum(len(o.val_index) for o in objects)} "
          f"validation touches ({n_img / 2**20:.0f} MiB of frames); {torch.get_num_threads()} threads",
          file=sys.stderr)

    def progress():
        p = 0.0
        if args.steps:
            p = max(p, step / args.steps)
        if budget_s:
            p = max(p, elapsed / budget_s)
        return p

    def checkpoint():
        save_atomic({"state_dict": model.state_dict(), "optimizer": opt.state_dict(), "step": step,
                     "elapsed_s": elapsed, "sampler": sampler.state(), "aug_rng": gen.get_state(),
                     "torch_rng": torch.get_rng_state(), "config": cfg,
                     "match": None if match is None else match.state_dict(), "args": {
                         k: getattr(args, k) for k in ("config", "seed", "batch", "lam", "lr", "minutes",
                                                       "steps", "val_fraction", "rotate", "match",
                                                       "feature_scale", "groups", "first_argv")}}, ckpt_path)

    warmup = min(100, max(1, args.steps // 10)) if args.steps else 100
    val = (None, None)
    if not args.export_only:
        log = Log(os.path.join(args.out, "log.csv"), step if ckpt is not None else None)
        bar = None
        if sys.stderr.isatty():
            from tqdm import tqdm
            bar = tqdm(total=args.steps or int(budget_s), initial=step if args.steps else int(elapsed),
                       unit="step" if args.steps else "s", dynamic_ncols=True)
        acc, acc_n, last_ckpt, last_log = np.zeros(4), 0, elapsed, step
        t_prev = time.perf_counter()
        model.train()
        model.point.eval()
        start_step = step
        while progress() < 1.0:
            # At fixed steps, so a resumed run recalibrates exactly where an uninterrupted one does.
            if step % args.bn_every == 0 if args.bn_every else step == 0:
                calibrate_point_bn(model, objects)
            batch = sampler.next()
            for g in opt.param_groups:
                g["lr"] = learning_rate(args.lr, step, progress(), warmup)
            loss, seq, rec, _, aux = group_losses(model, [(objects[k], i) for k, i in batch], args.lam, gen,
                                                  args.rotate, match, args.match, args.feature_scale)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            torch.nn.utils.clip_grad_norm_(params, 5.0)
            opt.step()
            step += 1
            acc += [float(loss), float(seq), float(rec), float(aux)]
            acc_n += 1
            now = time.perf_counter()
            elapsed += now - t_prev
            t_prev = now
            if bar is not None:
                bar.update(1 if args.steps else int(elapsed) - bar.n)
                bar.set_postfix(loss=f"{float(loss):.3f}")
            stop = args.stop_after is not None and step - start_step >= args.stop_after
            done = progress() >= 1.0 or stop
            if step - last_log >= args.log_every or done:
                m = acc / max(acc_n, 1)
                log.write(step=step, elapsed_s=elapsed, lr=opt.param_groups[0]["lr"], loss=m[0],
                          loss_seq=m[1], loss_recon=m[2], loss_aux=m[3] if match is not None or args.feature_scale > 0 else None)
                acc, acc_n, last_log = np.zeros(4), 0, step
            if elapsed - last_ckpt >= 60.0 * args.ckpt_minutes or done:
                val = validate_calibrated(model, objects, args.lam)
                log.write(step=step, elapsed_s=elapsed, val_loss=val[0], val_nd=val[1])
                checkpoint()
                if args.keep_every and int(elapsed / (60 * args.keep_every)) > int(last_ckpt / (60 * args.keep_every)):
                    # the equal-budget comparisons need this run as it stood at a shorter budget
                    mark = int(elapsed / (60 * args.keep_every)) * args.keep_every
                    shutil.copyfile(ckpt_path, os.path.join(args.out, f"checkpoint-{mark:g}min.pt"))
                last_ckpt = elapsed
                t_prev = time.perf_counter()  # validation and saving are not training time
            if stop:
                break
        if bar is not None:
            bar.close()
        if progress() < 1.0:
            print(f"stopped at step {step}; --resume continues", file=sys.stderr)
            return model, step, elapsed
    calibrate_point_bn(model, objects)  # the exported statistics match the final weights
    if val[0] is None:
        val = validate(model, objects, args.lam)
    out = os.path.join(args.out, "model.safetensors")
    export_weights(model, out, provenance(args, ds, objects, step, elapsed, val))
    print(f"{step} steps in {elapsed / 60:.1f} min ({step * args.batch / max(elapsed, 1e-9):.0f} "
          f"touches/s); validation ND {val[1] if val[1] is None else round(val[1], 2)} %; "
          f"wrote {out}", file=sys.stderr)
    return model, step, elapsed


def parse_args(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(prog="python3 -m weights_tools.train", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", help=f"named config: {', '.join(sorted(config_mod.NAMED))}")
    ap.add_argument("--data", required=True, help="dataset folder (docs/dataset.md)")
    ap.add_argument("--out", required=True, help="run folder")
    ap.add_argument("--minutes", type=float, help="training time budget (default 85 without --steps)")
    ap.add_argument("--steps", type=int, help="step budget")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--batch", type=int, default=16, help="touches per step (all of one object)")
    ap.add_argument("--objects-per-batch", dest="groups", type=int, default=1,
                    help="objects in a batch (batch/N touches of each; the point branch runs N times)")
    ap.add_argument("--lambda", dest="lam", type=float, default=1.0, help="weight of L_recon")
    ap.add_argument("--lr", type=float, default=3e-4)
    ap.add_argument("--match", type=float, default=1.0,
                    help="weight of the training-only local-matching loss (0: off)")
    ap.add_argument("--feature-scale", type=float, default=1.0,
                    help="weight of the training-only penalty keeping F^p and F^t near unit RMS (0: off)")
    ap.add_argument("--val-fraction", type=float, default=VAL_FRACTION)
    ap.add_argument("--rotate", action="store_true", help="also rotate the frames at random (a sensor spin)")
    ap.add_argument("--bn-every", type=int, default=50,
                    help="recompute the point branch's BatchNorm statistics every N steps (0: once)")
    ap.add_argument("--ckpt-minutes", type=float, default=5.0)
    ap.add_argument("--log-every", type=int, default=25)
    ap.add_argument("--keep-every", type=float, default=0,
                    help="also keep the checkpoint as checkpoint-<M>min.pt every M minutes of training")
    ap.add_argument("--threads", type=int, default=0, help="torch threads (0: all cores)")
    ap.add_argument("--resume", action="store_true", help="continue RUN_DIR/checkpoint.pt to its budget")
    ap.add_argument("--export-only", action="store_true", help="export RUN_DIR/checkpoint.pt and stop")
    ap.add_argument("--stop-after", type=int, help=argparse.SUPPRESS)  # tests: an interrupted run
    args = ap.parse_args(argv)
    if args.minutes is None and args.steps is None:
        args.minutes = 85.0
    if args.batch < 1:
        ap.error("--batch must be >= 1")
    args.argv = argv
    args.first_argv = argv  # replaced by the checkpoint's on --resume / --export-only
    return args


def main(argv=None):
    args = parse_args(argv)
    try:
        run(args)
    except (DatasetError, ValueError, KeyError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
