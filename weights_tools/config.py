"""Model configurations: the JSON dict stored in a weight file's
``__metadata__["vtloc.config"]``.  Schema documented in README.md."""

import copy
import json
import math

_TOP_KEYS = ("name", "C", "K", "tactile", "point", "gma", "ilu", "head", "mcr", "sensor")
_TACTILE_KEYS = ("crop", "in_size", "widths", "blocks", "mlp")
_POINT_KEYS = ("n_points", "use_normals", "sa", "group_all_mlp", "mlp")
_SA_KEYS = ("npoint", "radii", "nsample", "mlps")
_GMA_KEYS = ("n_points", "channels", "decoder")
_ILU_KEYS = ("iters", "head_hidden")
_MCR_KEYS = ("hidden",)
_SENSOR_KEYS = ("mm_per_px", "height", "width")

MAX_ITERS = 64  # SPEC 2: ILU iterations 0..64 at run time

_R18 = {
    "name": "vtloc-r18",
    "C": 128,
    "K": 5,
    "tactile": {"crop": 320, "in_size": 224, "widths": [64, 128, 256, 512],
                "blocks": [2, 2, 2, 2], "mlp": [256]},
    "point": {
        "n_points": 1024,
        "use_normals": True,
        "sa": [
            {"npoint": 512, "radii": [0.1, 0.2, 0.4], "nsample": [16, 32, 128],
             "mlps": [[32, 32, 64], [64, 64, 128], [64, 96, 128]]},
            {"npoint": 128, "radii": [0.2, 0.4, 0.8], "nsample": [32, 64, 128],
             "mlps": [[64, 64, 128], [128, 128, 256], [128, 128, 256]]},
        ],
        "group_all_mlp": [256, 512, 1024],
        "mlp": [512],
    },
    "gma": {"n_points": 1024, "channels": 64, "decoder": [64, 32, 16]},
    "ilu": {"iters": 16, "head_hidden": 64},
    "head": "ilu",
    "mcr": None,
}

_MCR = copy.deepcopy(_R18)
_MCR.update(name="vtloc-mcr", gma=None, ilu=None, head="mcr", mcr={"hidden": [256, 32]})
_MCR["point"]["use_normals"] = False

_TINY = {
    "name": "vtloc-tiny",
    "C": 16,
    "K": 5,
    # crop 128 > 120 rows of the synthetic image, so zero padding is exercised;
    # 128 -> 40 is a non-integer resize ratio.
    "tactile": {"crop": 128, "in_size": 40, "widths": [8, 16, 16, 32],
                "blocks": [1, 1, 1, 1], "mlp": [32]},
    "point": {
        "n_points": 128,
        "use_normals": True,
        "sa": [  # SSG: one scale per stage
            {"npoint": 32, "radii": [0.3], "nsample": [8], "mlps": [[16, 16, 32]]},
            {"npoint": 8, "radii": [0.8], "nsample": [12], "mlps": [[32, 32, 64]]},
        ],
        "group_all_mlp": [64, 64, 128],
        "mlp": [64],
    },
    "gma": {"n_points": 32, "channels": 8, "decoder": [16, 8, 8]},
    "ilu": {"iters": 4, "head_hidden": 16},
    "head": "ilu",
    "mcr": None,
}

_MCR_TINY = copy.deepcopy(_TINY)
_MCR_TINY.update(name="vtloc-mcr-tiny", gma=None, ilu=None, head="mcr", mcr={"hidden": [32, 8]})
_MCR_TINY["point"].update(use_normals=False, sa=[  # MSG: two scales per stage
    {"npoint": 32, "radii": [0.2, 0.4], "nsample": [8, 16], "mlps": [[8, 16], [16, 16]]},
    {"npoint": 8, "radii": [0.4, 0.8], "nsample": [8, 16], "mlps": [[16, 32], [16, 32]]},
])

# Lite configs: trainable on a 2-core CPU in about 90 minutes (see docs/training.md).
# Frames are 120 x 160, so crop 120 keeps the whole height and drops 20 columns a side.
_LITE = {
    "name": "vtloc-lite",
    "C": 64,
    "K": 5,
    "tactile": {"crop": 120, "in_size": 112, "widths": [16, 32, 64, 128],
                "blocks": [2, 2, 2, 2], "mlp": [128]},
    "point": {
        "n_points": 1024,
        "use_normals": True,
        "sa": [
            {"npoint": 256, "radii": [0.2], "nsample": [32], "mlps": [[32, 32, 64]]},
            {"npoint": 64, "radii": [0.4], "nsample": [32], "mlps": [[64, 64, 128]]},
        ],
        "group_all_mlp": [128, 256, 512],
        "mlp": [256],
    },
    "gma": {"n_points": 256, "channels": 16, "decoder": [32, 16, 8]},
    "ilu": {"iters": 16, "head_hidden": 32},
    "head": "ilu",
    "mcr": None,
}

# The synthetic dataset's sensor (`vtloc synth`): frames of 160 x 120 pixels of 0.1245 mm.
SYNTH_SENSOR = {"mm_per_px": 0.1245, "height": 120, "width": 160}
_LITE["sensor"] = dict(SYNTH_SENSOR)

_LITE_XYZ = copy.deepcopy(_LITE)
_LITE_XYZ["name"] = "vtloc-lite-xyz"
_LITE_XYZ["point"]["use_normals"] = False

_MCR_LITE = copy.deepcopy(_LITE)
_MCR_LITE.update(name="mcr-lite", gma=None, ilu=None, head="mcr", mcr={"hidden": [128, 32]})
_MCR_LITE["point"]["use_normals"] = False

# vtloc-tiny with a sensor: the same tensors (a test fixture of the rescale).
_TINY_SENSOR = copy.deepcopy(_TINY)
_TINY_SENSOR.update(name="vtloc-tiny-sensor", sensor=dict(SYNTH_SENSOR))

NAMED = {c["name"]: c for c in (_R18, _MCR, _TINY, _MCR_TINY, _LITE, _LITE_XYZ, _MCR_LITE, _TINY_SENSOR)}


def named(name):
    if name not in NAMED:
        raise KeyError(f"unknown config {name!r}; known: {sorted(NAMED)}")
    return canonical(NAMED[name])


def _keys(d, keys, where, optional=()):
    if not isinstance(d, dict):
        raise ValueError(f"{where}: expected an object")
    unknown = set(d) - set(keys)
    missing = set(keys) - set(d) - set(optional)
    if unknown or missing:
        raise ValueError(f"{where}: unknown keys {sorted(unknown)}, missing {sorted(missing)}")


def _ints(v, where, min_len=1):
    if not isinstance(v, list) or len(v) < min_len or not all(
            isinstance(x, int) and not isinstance(x, bool) and x > 0 for x in v):
        raise ValueError(f"{where}: expected a list of >= {min_len} positive ints")
    return list(v)


def _pos_int(v, where):
    if not isinstance(v, int) or isinstance(v, bool) or v <= 0:
        raise ValueError(f"{where}: expected a positive int")
    return v


def canonical(cfg):
    """Validate ``cfg`` and return a fresh dict with keys in schema order
    (so its JSON text is the same however it was built)."""
    _keys(cfg, _TOP_KEYS, "config", optional=("mcr", "sensor"))
    t, p = cfg["tactile"], cfg["point"]
    _keys(t, _TACTILE_KEYS, "tactile")
    if len(t["widths"]) != 4 or len(t["blocks"]) != 4:
        raise ValueError("tactile: widths and blocks need 4 entries (ResNet stages)")
    out = {
        "name": str(cfg["name"]),
        "C": _pos_int(cfg["C"], "C"),
        "K": _pos_int(cfg["K"], "K"),
        "tactile": {"crop": _pos_int(t["crop"], "tactile.crop"),
                    "in_size": _pos_int(t["in_size"], "tactile.in_size"),
                    "widths": _ints(t["widths"], "tactile.widths", 4),
                    "blocks": _ints(t["blocks"], "tactile.blocks", 4),
                    "mlp": _ints(t["mlp"], "tactile.mlp", 0)},
    }
    _keys(p, _POINT_KEYS, "point")
    if not isinstance(p["use_normals"], bool):
        raise ValueError("point.use_normals: expected a bool")
    if not isinstance(p["sa"], list) or not p["sa"]:
        raise ValueError("point.sa: expected a non-empty list of SA stages")
    stages = []
    for i, s in enumerate(p["sa"]):
        w = f"point.sa[{i}]"
        _keys(s, _SA_KEYS, w)
        radii = s["radii"]
        if not isinstance(radii, list) or not radii or not all(
                isinstance(r, (int, float)) and not isinstance(r, bool) and r > 0 for r in radii):
            raise ValueError(f"{w}.radii: expected a list of positive numbers")
        nsample = _ints(s["nsample"], f"{w}.nsample")
        mlps = s["mlps"]
        if not isinstance(mlps, list) or not (len(radii) == len(nsample) == len(mlps)):
            raise ValueError(f"{w}: radii, nsample and mlps need one entry per scale")
        stages.append({"npoint": _pos_int(s["npoint"], f"{w}.npoint"),
                       "radii": [float(r) for r in radii], "nsample": nsample,
                       "mlps": [_ints(m, f"{w}.mlps") for m in mlps]})
    out["point"] = {"n_points": _pos_int(p["n_points"], "point.n_points"),
                    "use_normals": p["use_normals"], "sa": stages,
                    "group_all_mlp": _ints(p["group_all_mlp"], "point.group_all_mlp"),
                    "mlp": _ints(p["mlp"], "point.mlp", 0)}
    g = cfg["gma"]
    if g is not None:
        _keys(g, _GMA_KEYS, "gma")
        g = {"n_points": _pos_int(g["n_points"], "gma.n_points"),
             "channels": _pos_int(g["channels"], "gma.channels"),
             "decoder": _ints(g["decoder"], "gma.decoder", 0)}
    out["gma"] = g
    il = cfg["ilu"]
    if il is not None:
        _keys(il, _ILU_KEYS, "ilu")
        iters = il["iters"]
        if not isinstance(iters, int) or isinstance(iters, bool) or not 0 <= iters <= MAX_ITERS:
            raise ValueError(f"ilu.iters: expected an int in 0..{MAX_ITERS}")
        il = {"iters": iters, "head_hidden": _pos_int(il["head_hidden"], "ilu.head_hidden")}
    out["ilu"] = il
    head = cfg["head"]
    m = cfg.get("mcr")
    if head == "ilu":
        if il is None:
            raise ValueError("head 'ilu' needs an ilu section")
    elif head == "mcr":
        if m is None:
            raise ValueError("head 'mcr' needs an mcr section")
    else:
        raise ValueError("head: expected 'ilu' or 'mcr'")
    out["head"] = head
    if m is not None:
        _keys(m, _MCR_KEYS, "mcr")
        m = {"hidden": _ints(m["hidden"], "mcr.hidden", 0)}
    out["mcr"] = m
    sensor = cfg.get("sensor")
    if sensor is not None:  # absent (or null): no sensor recorded, the key stays out
        out["sensor"] = canonical_sensor(sensor)
    return out


def canonical_sensor(s):
    """The optional ``sensor`` section: the pixel size (mm) and frame size the
    model was trained on.  A frame with another pixel size is rescaled to it."""
    _keys(s, _SENSOR_KEYS, "sensor")
    mm = s["mm_per_px"]
    if isinstance(mm, bool) or not isinstance(mm, (int, float)) or not math.isfinite(mm) or mm <= 0:
        raise ValueError("sensor.mm_per_px: expected a finite number > 0")
    return {"mm_per_px": float(mm), "height": _pos_int(s["height"], "sensor.height"),
            "width": _pos_int(s["width"], "sensor.width")}


def to_json(cfg):
    return json.dumps(canonical(cfg), separators=(",", ":"))


def from_json(text):
    return canonical(json.loads(text))


def point_in_channels(cfg):
    """Per-point feature channels fed to SA1 besides xyz (normals or none)."""
    return 3 if cfg["point"]["use_normals"] else 0
