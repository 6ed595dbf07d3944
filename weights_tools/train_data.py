"""Training data for weights_tools.train: the seen objects in memory, their
train/validation split, the point branch with precomputed sampling, batch-order
sampling and the batched (augmented) tactile preprocessing."""

import hashlib
import math
import zlib

import numpy as np
import torch
import torch.nn.functional as F

from . import post
from .dataset import DatasetError
from .pointnet2 import gather, run_stack
from .tactile import IMAGENET_MEAN, IMAGENET_STD, center_crop, crop_start

VAL_FRACTION = 0.1      # share of each seen object's train contacts held out
EXTRA_CLEARANCE_MM = 2.0  # extra renders this close to a held-out contact are dropped too


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


def seen_splits(ds, fraction=VAL_FRACTION):
    """(object, training ids, validation ids) of each seen object: what train.py and
    pretrain.py read."""
    return [(obj, *split_contacts(obj, fraction)) for obj in ds.objects if obj.object_split == "seen"]


def training_fingerprint(ds, fraction=VAL_FRACTION):
    """Names the training touches (seen objects, ids and contacts to 1 um) of a dataset and
    validation share: equal wherever the same data is read, whatever its folder."""
    h = hashlib.sha256()
    for obj, ids, _ in seen_splits(ds, fraction):
        by_id = {t.id: t for t in obj.touches}
        h.update(obj.name.encode() + b"\0")
        for i in ids:
            h.update(np.int64(i).tobytes() + np.round(np.asarray(by_id[i].contact, dtype=np.float64), 3).tobytes())
    return h.hexdigest()[:16]


def load_objects(model, ds, fraction=VAL_FRACTION):
    out = [TrainObject(model, obj, tr, va) for obj, tr, va in seen_splits(ds, fraction) if tr]
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


# ---------------------------------------------------------------- sampling

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
