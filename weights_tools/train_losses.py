"""Training losses of weights_tools.train (SPEC 4 sequence and reconstruction
losses, the training-only auxiliary terms) and validation."""

import math

import numpy as np
import torch
import torch.nn.functional as F

from .train_data import calibrate_point_bn, images_to_input, point_features

GAMMA = 0.9             # SPEC 4 sequence-loss decay


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
