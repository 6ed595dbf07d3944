"""Train a VTLoc config on a vtloc-synth/1 dataset and export the weight file.

  python3 -m weights_tools.train --config vtloc-lite --data DIR --out RUN_DIR
      [--minutes M] [--steps S] [--seed 0] [--batch 16] [--lambda 1.0] [--resume]
      [--export-only] [--init-tactile PRETRAIN_RUN/tactile.pt [--freeze-tactile]] [--keep-best]

Trains on the ``train`` and ``extra`` touches of the ``seen`` objects; a fixed share of
each seen object's ``train`` contacts is held out for validation (test touches are never
read).  A batch holds touches of one object, so the point encoder runs once per batch.
Writes RUN_DIR/checkpoint.pt (atomically, every few minutes), RUN_DIR/log.csv and at the
end RUN_DIR/model.safetensors with ``vtloc.provenance`` metadata; with --keep-best also
RUN_DIR/best.pt (the checkpoint of the lowest validation ND so far) and, at the end, its
export RUN_DIR/model-best.safetensors.  See docs/training.md.
"""

import argparse
import csv
import json
import math
import os
import pickle
import shutil
import subprocess
import sys
import time

import numpy as np
import torch

from . import config as config_mod
from . import model as model_mod
from . import safetensors_io
from .dataset import DatasetError, read_dataset
# Data handling and losses live in train_data / train_losses; the names are re-exported
# here because tests and scripts use them as weights_tools.train.<name>.
from .train_data import (EXTRA_CLEARANCE_MM, VAL_FRACTION, Sampler, TrainObject,  # noqa: F401
                         _normalise, calibrate_point_bn, images_to_input, load_objects,
                         point_features, rotated_crops, sampling_plan, split_contacts, training_fingerprint)
from .train_losses import (GAMMA, LocalMatch, chamfer_batch, feature_scale, group_losses,  # noqa: F401
                           losses, validate, validate_calibrated)

LOG_COLUMNS = ("step", "elapsed_s", "lr", "loss", "loss_seq", "loss_recon", "val_loss", "val_nd",
               "loss_aux")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


# ---------------------------------------------------------------- schedule

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


def load_file(path, what, keys):
    """A torch.save dict holding ``keys`` -> it; anything else a ValueError naming the file."""
    try:
        got = torch.load(path, map_location="cpu")
    except (OSError, EOFError, RuntimeError, ValueError, pickle.UnpicklingError, AttributeError) as e:
        raise ValueError(f"{path}: not a readable {what} ({type(e).__name__}: {e})") from None
    if not isinstance(got, dict) or any(k not in got for k in keys):
        raise ValueError(f"{path}: not a {what}")
    return got


def init_tactile(model, path, args, touches):
    """Start the tactile encoder from weights_tools.pretrain's tactile.pt, which must have
    been pretrained with the same config on the same training touches (``touches``:
    train_data.training_fingerprint; other touches may include this run's validation
    contacts)."""
    got = load_file(path, "weights_tools.pretrain tactile.pt", ("settings", "tactile"))
    was = got["settings"]
    for k, now in (("config", args.config), ("val_fraction", args.val_fraction), ("touches", touches)):
        if was.get(k) != now:
            raise ValueError(f"{path}: pretrained with {k} {was.get(k)} ({was.get('data')}), this run has {now}")
    try:
        model.tactile.load_state_dict(got["tactile"])
    except RuntimeError as e:
        raise ValueError(f"{path}: does not fit config {args.config} ({e})") from None


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
        "init_tactile": args.init_tactile, "freeze_tactile": args.freeze_tactile, "val_loss": val[0], "val_nd": val[1], "git_commit": commit, "git_dirty": dirty,
        # the command that started the run (a resume or --export-only keeps it), then this one
        "command": " ".join([os.path.basename(sys.executable), "-m", "weights_tools.train"] + args.first_argv),
        "last_command": " ".join([os.path.basename(sys.executable), "-m", "weights_tools.train"] + args.argv),
        "torch": torch.__version__,
    }

def load_checkpoint(args, ckpt_path):
    """The run folder's checkpoint (None for a new run); on --resume / --export-only
    the run's own settings replace the command line's, so it continues the same run."""
    if not os.path.exists(ckpt_path):
        if args.export_only:
            raise ValueError(f"{ckpt_path}: missing (nothing to export)")
        return None
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
    args.init_tactile = saved.get("init_tactile")
    args.freeze_tactile = saved.get("freeze_tactile", False)
    args.keep_best = saved.get("keep_best", False)
    args.first_argv = saved.get("first_argv", args.argv)
    return ckpt


class Trainer:
    """One run's state (model, optimiser, batch order, RNGs, step, training time) and
    what run() does with it.  Construction draws from the torch RNG in a fixed order
    (model, then LocalMatch) before a checkpoint restores every state, so a resumed run
    continues exactly where the uninterrupted one would be."""

    def __init__(self, args, ckpt_path, ckpt):
        self.args, self.ckpt_path = args, ckpt_path
        self.cfg = cfg = config_mod.named(args.config)
        torch.set_num_threads(args.threads or os.cpu_count() or 1)
        self.ds = read_dataset(args.data)
        self.model = make_model(cfg, args.seed)
        if args.init_tactile and ckpt is None:  # a resumed run has the weights in its checkpoint
            init_tactile(self.model, args.init_tactile, args, training_fingerprint(self.ds, args.val_fraction))
        if args.freeze_tactile:  # F^t as pretrained: no gradient, BatchNorm statistics kept
            for p in self.model.tactile.parameters():
                p.requires_grad_(False)
        self.objects = load_objects(self.model, self.ds, args.val_fraction)
        self.match = LocalMatch(cfg) if args.match > 0 else None  # seeded by make_model's manual_seed
        self.params = [p for p in self.model.parameters() if p.requires_grad]
        n_model = sum(p.numel() for p in self.params)
        if self.match is not None:
            self.params += list(self.match.parameters())
        self.opt = torch.optim.AdamW(self.params, lr=args.lr, weight_decay=1e-4)
        self.sampler = Sampler(self.objects, args.batch, args.seed, args.groups)
        self.gen = torch.Generator().manual_seed(args.seed)
        self.step, self.elapsed = 0, 0.0
        self.best_nd = None  # --keep-best: the lowest validation ND so far (kept in the checkpoint)
        if ckpt is not None:
            self._restore(ckpt)
        self.budget_s = None if args.minutes is None else 60.0 * args.minutes
        objects = self.objects
        n_img = sum(o.images.numel() for o in objects)
        print(f"{cfg['name']}: {n_model} parameters; {len(objects)} objects, "
              f"{sum(o.n_train for o in objects)} training / {sum(len(o.val_index) for o in objects)} "
              f"validation touches ({n_img / 2**20:.0f} MiB of frames); {torch.get_num_threads()} threads",
              file=sys.stderr)

    def _restore(self, ckpt):
        self.model.load_state_dict(ckpt["state_dict"])
        if self.match is not None:
            self.match.load_state_dict(ckpt["match"])
        self.opt.load_state_dict(ckpt["optimizer"])
        self.step, self.elapsed = ckpt["step"], ckpt["elapsed_s"]
        self.best_nd = ckpt.get("best_val_nd")
        self.sampler.load(ckpt["sampler"])
        self.gen.set_state(ckpt["aug_rng"])
        torch.set_rng_state(ckpt["torch_rng"])

    def progress(self):
        """Share of the budget spent: the larger of steps and training time."""
        p = 0.0
        if self.args.steps:
            p = max(p, self.step / self.args.steps)
        if self.budget_s:
            p = max(p, self.elapsed / self.budget_s)
        return p

    def checkpoint(self):
        args = self.args
        save_atomic({"state_dict": self.model.state_dict(), "optimizer": self.opt.state_dict(),
                     "step": self.step, "elapsed_s": self.elapsed, "sampler": self.sampler.state(),
                     "best_val_nd": self.best_nd,
                     "aug_rng": self.gen.get_state(), "torch_rng": torch.get_rng_state(), "config": self.cfg,
                     "match": None if self.match is None else self.match.state_dict(), "args": {
                         k: getattr(args, k) for k in ("config", "seed", "batch", "lam", "lr", "minutes",
                                                       "steps", "val_fraction", "rotate", "match",
                                                       "feature_scale", "groups", "init_tactile", "freeze_tactile",
                                                       "keep_best", "first_argv")}},
                    self.ckpt_path)

    def train_step(self, warmup):
        """One optimiser step on the next batch -> (loss, seq, recon, aux)."""
        args, model, objects = self.args, self.model, self.objects
        # At fixed steps, so a resumed run recalibrates exactly where an uninterrupted one does.
        if self.step % args.bn_every == 0 if args.bn_every else self.step == 0:
            calibrate_point_bn(model, objects)
        batch = self.sampler.next()
        self.model.tactile.train(not args.freeze_tactile)  # validation may have set train mode
        for g in self.opt.param_groups:
            g["lr"] = learning_rate(args.lr, self.step, self.progress(), warmup)
        loss, seq, rec, _, aux = group_losses(model, [(objects[k], i) for k, i in batch], args.lam, self.gen,
                                              args.rotate, self.match, args.match, args.feature_scale)
        self.opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.params, 5.0)
        self.opt.step()
        self.step += 1
        return loss, seq, rec, aux

    def validate_and_checkpoint(self, log, last_ckpt):
        """Validation row, checkpoint, (--keep-every) its timed copy and (--keep-best) its
        copy as best.pt when the validation ND is the run's lowest -> (loss, ND)."""
        args = self.args
        val = validate_calibrated(self.model, self.objects, args.lam)
        log.write(step=self.step, elapsed_s=self.elapsed, val_loss=val[0], val_nd=val[1])
        better = args.keep_best and val[1] is not None and (self.best_nd is None or val[1] < self.best_nd)
        if better:
            self.best_nd = val[1]
        self.checkpoint()
        if better:
            shutil.copyfile(self.ckpt_path, os.path.join(args.out, "best.pt.tmp"))
            os.replace(os.path.join(args.out, "best.pt.tmp"), os.path.join(args.out, "best.pt"))
        if args.keep_every and int(self.elapsed / (60 * args.keep_every)) > int(last_ckpt / (60 * args.keep_every)):
            # the equal-budget comparisons need this run as it stood at a shorter budget
            mark = int(self.elapsed / (60 * args.keep_every)) * args.keep_every
            shutil.copyfile(self.ckpt_path, os.path.join(args.out, f"checkpoint-{mark:g}min.pt"))
        return val

    def _progress_bar(self):
        if not sys.stderr.isatty():
            return None
        from tqdm import tqdm
        steps = self.args.steps
        return tqdm(total=steps or int(self.budget_s), initial=self.step if steps else int(self.elapsed),
                    unit="step" if steps else "s", dynamic_ncols=True)

    def train(self, resumed):
        """Steps until the budget (or --stop-after) -> the last (val loss, val ND)."""
        args = self.args
        warmup = min(100, max(1, args.steps // 10)) if args.steps else 100
        val = (None, None)
        log = Log(os.path.join(args.out, "log.csv"), self.step if resumed else None)
        bar = self._progress_bar()
        acc, acc_n, last_ckpt, last_log = np.zeros(4), 0, self.elapsed, self.step
        t_prev = time.perf_counter()
        self.model.train()
        self.model.point.eval()
        start_step = self.step
        while self.progress() < 1.0:
            loss, seq, rec, aux = self.train_step(warmup)
            acc += [float(loss), float(seq), float(rec), float(aux)]
            acc_n += 1
            now = time.perf_counter()
            self.elapsed += now - t_prev
            t_prev = now
            if bar is not None:
                bar.update(1 if args.steps else int(self.elapsed) - bar.n)
                bar.set_postfix(loss=f"{float(loss):.3f}")
            stop = args.stop_after is not None and self.step - start_step >= args.stop_after
            done = self.progress() >= 1.0 or stop
            if self.step - last_log >= args.log_every or done:
                m = acc / max(acc_n, 1)
                log.write(step=self.step, elapsed_s=self.elapsed, lr=self.opt.param_groups[0]["lr"], loss=m[0],
                          loss_seq=m[1], loss_recon=m[2],
                          loss_aux=m[3] if self.match is not None or args.feature_scale > 0 else None)
                acc, acc_n, last_log = np.zeros(4), 0, self.step
            if self.elapsed - last_ckpt >= 60.0 * args.ckpt_minutes or done:
                val = self.validate_and_checkpoint(log, last_ckpt)
                last_ckpt = self.elapsed
                t_prev = time.perf_counter()  # validation and saving are not training time
            if stop:
                break
        if bar is not None:
            bar.close()
        return val

    def export(self, val):
        """RUN_DIR/model.safetensors with statistics of the final weights."""
        model, objects, args = self.model, self.objects, self.args
        calibrate_point_bn(model, objects)  # the exported statistics match the final weights
        if val[0] is None:
            val = validate(model, objects, args.lam)
        out = os.path.join(args.out, "model.safetensors")
        export_weights(model, out, provenance(args, self.ds, objects, self.step, self.elapsed, val))
        step, elapsed = self.step, self.elapsed
        print(f"{step} steps in {elapsed / 60:.1f} min ({step * args.batch / max(elapsed, 1e-9):.0f} "
              f"touches/s); validation ND {val[1] if val[1] is None else round(val[1], 2)} %; "
              f"wrote {out}", file=sys.stderr)
        if args.keep_best:
            self.export_best()

    def export_best(self):
        """RUN_DIR/model-best.safetensors from best.pt: the weights of the run's lowest
        validation ND, statistics recomputed and validated again for the provenance."""
        args, objects = self.args, self.objects
        path = os.path.join(args.out, "best.pt")
        if not os.path.exists(path):
            raise ValueError(f"{path}: missing (no validation ran with --keep-best)")
        best = load_file(path, "checkpoint", ("state_dict", "step", "elapsed_s"))
        model = make_model(self.cfg, args.seed)
        model.load_state_dict(best["state_dict"])
        calibrate_point_bn(model, objects)
        val = validate(model, objects, args.lam)
        out = os.path.join(args.out, "model-best.safetensors")
        export_weights(model, out, provenance(args, self.ds, objects, best["step"], best["elapsed_s"], val))
        print(f"best validation ND {round(val[1], 2)} % at step {best['step']}; wrote {out}", file=sys.stderr)


def run(args):
    """Train (or continue) the run in args.out and export it -> (model, step, elapsed)."""
    os.makedirs(args.out, exist_ok=True)
    ckpt_path = os.path.join(args.out, "checkpoint.pt")
    ckpt = load_checkpoint(args, ckpt_path)
    if args.config is None:
        raise ValueError("--config is required")
    t = Trainer(args, ckpt_path, ckpt)
    val = (None, None)
    if not args.export_only:
        val = t.train(ckpt is not None)
        if t.progress() < 1.0:
            print(f"stopped at step {t.step}; --resume continues", file=sys.stderr)
            return t.model, t.step, t.elapsed
    t.export(val)
    return t.model, t.step, t.elapsed


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
    ap.add_argument("--init-tactile", help="start the tactile encoder from weights_tools.pretrain's tactile.pt")
    ap.add_argument("--freeze-tactile", action="store_true",
                    help="train everything but the tactile encoder (with --init-tactile: a probe of the pretrained F^t)")
    ap.add_argument("--bn-every", type=int, default=50,
                    help="recompute the point branch's BatchNorm statistics every N steps (0: once)")
    ap.add_argument("--ckpt-minutes", type=float, default=5.0)
    ap.add_argument("--log-every", type=int, default=25)
    ap.add_argument("--keep-every", type=float, default=0,
                    help="also keep the checkpoint as checkpoint-<M>min.pt every M minutes of training")
    ap.add_argument("--keep-best", action="store_true",
                    help="keep the checkpoint of the lowest validation ND as best.pt; export it too, as model-best.safetensors")
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


def cli_main(run_fn, args):
    """Run a tool; a bad input is one line on stderr and exit status 2."""
    try:
        run_fn(args)
    except (DatasetError, ValueError, KeyError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


def main(argv=None):
    return cli_main(run, parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
