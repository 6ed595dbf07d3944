"""Contrastive pretraining of the tactile encoder on our own renders (issue 44).

  python3 -m weights_tools.pretrain --config vtloc-lite --data DIR --out RUN_DIR
      [--minutes M | --steps S] [--places 16] [--temperature 0.1] [--resume]

The positives are two renders of one contact: a dataset built with ``vtloc synth
--extra-views V`` renders each extra contact V times, each with its own spin, press,
tilt and look, so what two views share is the place, not the nuisances.  A contact
with one render is paired with a second augmentation of itself.  Every other frame in
the batch is a negative (NT-Xent, as in SimCLR).  Only the touches weights_tools.train
trains on are read (its validation contacts and every test touch stay unseen), so a
model fine-tuned from the result validates as fairly as one trained from scratch.

Writes RUN_DIR/checkpoint.pt (resumable: --resume continues with the checkpoint's settings),
RUN_DIR/log.csv and RUN_DIR/tactile.pt (the encoder's state dict and the run's settings;
``weights_tools.train --init-tactile`` starts from it on the same training touches).  The log's
``retrieval`` column: on about 10 % of the multi-render places, held out here, the share of first views
whose nearest second view (cosine on F^t, among those places' second views) is of the same
place; ``retrieval_chance`` is 1 / n.  Only places with several renders can be held out.
"""

import argparse
import csv
import os
import sys
import time
import zlib

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

from . import config as config_mod
from . import model as model_mod
from .dataset import DatasetError, read_dataset
from .train import cli_main, load_file, save_atomic
from .train_data import VAL_FRACTION, images_to_input, seen_splits, training_fingerprint

HELD_SHARE = 0.1  # places held out of pretraining to measure retrieval
LOG_COLUMNS = ("step", "elapsed_s", "loss", "retrieval", "retrieval_chance")
SAME_PLACE_MM = 1e-3  # renders of one contact differ in the last digits of its CSV row


def places(touches):
    """Consecutive touches at one contact (``--extra-views``' runs) grouped -> lists of ids."""
    groups, first = [], None
    for t in touches:
        c = np.asarray(t.contact, dtype=np.float64)
        if first is not None and np.linalg.norm(c - first) <= SAME_PLACE_MM:
            groups[-1].append(t.id)
        else:
            groups.append([t.id])
            first = c
    return groups


class Frames:
    """The training touches of every seen object, as places of one or more frames."""

    def __init__(self, ds, fraction=VAL_FRACTION):
        imgs, self.train, self.held = [], [], []
        for obj, train_ids, _ in seen_splits(ds, fraction):
            ids = set(train_ids)
            by_id = {t.id: t for t in obj.touches}
            rng = np.random.default_rng(zlib.crc32(obj.name.encode()))
            for group in places([t for t in obj.touches if t.id in ids]):
                rows = list(range(len(imgs), len(imgs) + len(group)))
                imgs += [obj.image(by_id[i]) for i in group]
                (self.held if rng.random() < HELD_SHARE and len(group) > 1 else self.train).append(rows)
        if len(self.train) < 2:  # one place has no negative: the loss would be 0
            raise DatasetError(f"{ds.root}: pretraining needs training touches at two places or more")
        if len({f.shape for f in imgs}) > 1:
            raise DatasetError(f"{ds.root}: frames of different sizes")
        self.images = torch.from_numpy(np.stack(imgs))


class Projection(nn.Module):
    """F^t -> the unit vector the loss compares (dropped after pretraining, as in SimCLR)."""

    def __init__(self, c, out=64):
        super().__init__()
        self.net = nn.Sequential(nn.Linear(c, c), nn.ReLU(), nn.Linear(c, out))

    def forward(self, x):
        return F.normalize(self.net(x), dim=-1)


def nt_xent(z1, z2, temperature):
    """Each of the 2P unit vectors against the other 2P - 1: its pair is the positive."""
    z = torch.cat([z1, z2])
    sim = z @ z.t() / temperature
    sim.fill_diagonal_(float("-inf"))
    p = z1.shape[0]
    target = torch.cat([torch.arange(p, 2 * p), torch.arange(p)])
    return F.cross_entropy(sim, target)


def batch_views(frames, rng, n):
    """n distinct places, two rows each (two renders where the place has them)."""
    pick = rng.choice(len(frames.train), size=min(n, len(frames.train)), replace=False)
    a, b = [], []
    for k in pick:
        rows = frames.train[k]
        i, j = rng.choice(len(rows), size=2, replace=len(rows) < 2)
        a.append(rows[i])
        b.append(rows[j])
    return a, b


@torch.no_grad()
def retrieval(encoder, frames, cfg):
    """Share of held-out places whose first view's nearest second view is its own -> (share, chance)."""
    if len(frames.held) < 2:
        return None, None
    was = encoder.training
    encoder.eval()
    f1 = F.normalize(encoder(images_to_input(frames.images[[r[0] for r in frames.held]], cfg)), dim=-1)
    f2 = F.normalize(encoder(images_to_input(frames.images[[r[1] for r in frames.held]], cfg)), dim=-1)
    encoder.train(was)
    hit = (f1 @ f2.t()).argmax(1) == torch.arange(len(frames.held))
    return hit.float().mean().item(), 1.0 / len(frames.held)


SETTINGS = ("config", "val_fraction", "places", "temperature", "lr", "seed")


def settings(args, touches):
    """What makes a run the same run; ``touches`` (train_data.training_fingerprint) and
    ``val_fraction`` are what train.py --init-tactile checks."""
    return dict({k: getattr(args, k) for k in SETTINGS}, data=os.path.abspath(args.data), touches=touches)


def _resume(ck, ckpt_path, args, encoder, head, opt, gen, touches):
    """Continue the checkpoint ``ck`` (its settings already in args) on the same training touches."""
    if ck["settings"].get("touches") != touches:
        raise ValueError(f"{ckpt_path}: pretrained on other training touches ({ck['settings'].get('data')}) "
                         f"than {os.path.abspath(args.data)}'s")
    try:
        encoder.load_state_dict(ck["encoder"])
        head.load_state_dict(ck["head"])
        opt.load_state_dict(ck["optimizer"])
    except (RuntimeError, ValueError) as e:
        raise ValueError(f"{ckpt_path}: does not fit config {args.config} ({e})") from None
    gen.set_state(ck["aug_rng"])
    return ck["step"], ck["elapsed_s"]


def _open_log(path, resume_step):
    """log.csv for appending; on resume without the rows written after the checkpoint."""
    rows = []
    if resume_step is not None and os.path.exists(path):
        with open(path, newline="") as f:
            rows = [r for r in csv.DictReader(f) if int(r["step"]) <= resume_step]
    f = open(path, "w", newline="")
    log = csv.DictWriter(f, LOG_COLUMNS)
    log.writeheader()
    log.writerows(rows)
    return f, log, bool(rows)


def run(args):
    """Pretrain (or continue) the run in args.out -> (encoder, step)."""
    os.makedirs(args.out, exist_ok=True)
    ckpt_path = os.path.join(args.out, "checkpoint.pt")
    if os.path.exists(ckpt_path) and not args.resume:
        raise ValueError(f"{ckpt_path}: exists; pass --resume to continue it or use another --out")
    ck = None
    if args.resume and os.path.exists(ckpt_path):  # its settings replace the command line's
        ck = load_file(ckpt_path, "weights_tools.pretrain checkpoint",
                       ("settings", "encoder", "head", "optimizer", "aug_rng", "step", "elapsed_s"))
        for k in SETTINGS:
            setattr(args, k, ck["settings"][k])
    cfg = config_mod.named(args.config)
    ds = read_dataset(args.data)
    touches = training_fingerprint(ds, args.val_fraction)
    torch.set_num_threads(args.threads or os.cpu_count() or 1)
    torch.manual_seed(args.seed)
    encoder = model_mod.VTLoc(cfg).tactile.train()  # the same initialisation train.py's model gets
    head = Projection(cfg["C"])
    params = list(encoder.parameters()) + list(head.parameters())
    opt = torch.optim.AdamW(params, lr=args.lr, weight_decay=1e-4)
    gen = torch.Generator().manual_seed(args.seed)
    step, elapsed = (0, 0.0) if ck is None else _resume(ck, ckpt_path, args, encoder, head, opt, gen, touches)
    frames = Frames(ds, args.val_fraction)
    multi = sum(len(r) > 1 for r in frames.train)
    print(f"{args.config} tactile encoder: {len(frames.train)} places ({multi} with several renders), "
          f"{len(frames.held)} held out; {frames.images.shape[0]} frames", file=sys.stderr)
    f, log, kept = _open_log(os.path.join(args.out, "log.csv"), None if ck is None else step)
    with f:
        if not kept:
            share, chance = retrieval(encoder, frames, cfg)
            log.writerow({"step": 0, "elapsed_s": 0, "retrieval": share, "retrieval_chance": chance})
        last_ckpt = time.monotonic()
        while (args.steps is None or step < args.steps) and (args.minutes is None or elapsed < 60 * args.minutes):
            t0 = time.monotonic()
            rng = np.random.default_rng([args.seed, step])
            a, b = batch_views(frames, rng, args.places)
            x = images_to_input(frames.images[a + b], cfg, gen)
            z = head(encoder(x))
            loss = nt_xent(z[:len(a)], z[len(a):], args.temperature)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            step += 1
            elapsed += time.monotonic() - t0
            done = (args.steps is not None and step >= args.steps) or \
                   (args.minutes is not None and elapsed >= 60 * args.minutes)
            if step % args.log_every == 0 or done:
                share, chance = retrieval(encoder, frames, cfg) if (step % (10 * args.log_every) == 0 or done) \
                    else (None, None)
                log.writerow({"step": step, "elapsed_s": round(elapsed, 1), "loss": round(loss.item(), 5),
                              "retrieval": share, "retrieval_chance": chance})
                f.flush()
            stop = args.stop_after is not None and step >= args.stop_after
            if done or stop or time.monotonic() - last_ckpt > 60 * args.ckpt_minutes:
                save_atomic({"settings": settings(args, touches), "encoder": encoder.state_dict(), "head": head.state_dict(),
                             "optimizer": opt.state_dict(), "aug_rng": gen.get_state(), "step": step,
                             "elapsed_s": elapsed}, ckpt_path)
                last_ckpt = time.monotonic()
            if stop and not done:
                return encoder, step
    out = os.path.join(args.out, "tactile.pt")
    save_atomic({"settings": settings(args, touches), "tactile": encoder.state_dict(), "steps": step}, out)
    share, chance = retrieval(encoder, frames, cfg)
    print(f"{step} steps in {elapsed / 60:.1f} min; held-out retrieval {share} (chance {chance}); wrote {out}",
          file=sys.stderr)
    return encoder, step


def parse_args(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m weights_tools.pretrain", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", required=True, help=f"named config: {', '.join(sorted(config_mod.NAMED))}")
    ap.add_argument("--data", required=True, help="dataset folder (docs/dataset.md)")
    ap.add_argument("--out", required=True, help="run folder")
    ap.add_argument("--minutes", type=float, help="training time budget")
    ap.add_argument("--steps", type=int, help="step budget")
    ap.add_argument("--places", type=int, default=16, help="places per batch (two frames each)")
    ap.add_argument("--temperature", type=float, default=0.1, help="NT-Xent temperature (SimCLR's usual value)")
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--val-fraction", type=float, default=VAL_FRACTION,
                    help="as weights_tools.train's: its validation contacts are never read here")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--log-every", type=int, default=25)
    ap.add_argument("--ckpt-minutes", type=float, default=5.0)
    ap.add_argument("--resume", action="store_true", help="continue RUN_DIR/checkpoint.pt to its budget")
    ap.add_argument("--stop-after", type=int, help=argparse.SUPPRESS)  # tests: an interrupted run
    args = ap.parse_args(argv)
    if args.minutes is None and args.steps is None:
        ap.error("give --minutes or --steps")
    if args.places < 2 or not args.temperature > 0:
        ap.error("--places must be >= 2 and --temperature > 0")
    return args


def main(argv=None):
    return cli_main(run, parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
