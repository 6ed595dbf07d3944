"""Reader of a ``vtloc-synth/1`` dataset folder (docs/dataset.md) without the engine.

    ds = read_dataset("DIR")
    obj = ds.objects[0]
    obj.points          # N x 6 float64, mm
    obj.candidates      # M x 3 float64: the test contacts in id order (S^c)
    obj.touches         # Touch records in id order
    obj.image(touch)    # H x W x 3 uint8 RGB, read on demand

Every problem is a ``DatasetError`` whose one-line message names the file.
"""

import csv
import json
import os
from dataclasses import dataclass, field

import numpy as np

FORMAT = "vtloc-synth/1"
SPLITS = ("train", "test", "extra")
SUBSETS = ("uniform", "non-uniform")
OBJECT_SPLITS = ("seen", "unseen")

POINT_COLUMNS = ("x", "y", "z", "nx", "ny", "nz")
_R = tuple(f"r{i}{j}" for i in range(3) for j in range(3))
_Q = tuple(f"q{i}{j}" for i in range(3) for j in range(3))
# docs/dataset.md lists every column; all are required so a file that lost one is caught
TOUCH_COLUMNS = (("id", "split", "order", "image", "cx", "cy", "cz", "nx", "ny", "nz") + _R
                 + ("tx", "ty", "tz", "press_mm", "spin_deg", "tilt_deg", "dx", "dy", "dz")
                 + _Q + ("qx", "qy", "qz"))


class DatasetError(ValueError):
    pass


@dataclass
class Touch:
    id: int
    split: str
    order: int
    image: str                 # relative to the object folder
    contact: np.ndarray        # 3, mm
    normal: np.ndarray         # 3
    R: np.ndarray              # 3 x 3, columns = sensor x, y, z in object coordinates
    t: np.ndarray              # 3, sensor centre, mm
    press_mm: float
    spin_deg: float
    tilt_deg: float
    motion: np.ndarray         # 3: sensor-centre translation from the previous touch, mm
    rel_R: np.ndarray          # 3 x 3
    rel_t: np.ndarray          # 3


@dataclass
class DatasetObject:
    name: str
    folder: str
    subset: str
    dn_share: float
    object_split: str
    scale_mm: float
    diameter_mm: float
    n_points: int
    sample_seed: int
    source: str
    points: np.ndarray                      # N x 6 float64, mm
    touches: list = field(default_factory=list)  # Touch, in id order

    @property
    def candidates(self):
        """S^c: the contacts of the test touches in id order (M x 3, mm)."""
        c = [t.contact for t in self.touches if t.split == "test"]
        return np.array(c, dtype=np.float64).reshape(len(c), 3)

    @property
    def candidate_ids(self):
        return [t.id for t in self.touches if t.split == "test"]

    def touches_of(self, *splits):
        return [t for t in self.touches if t.split in splits]

    def image_path(self, touch):
        return os.path.join(self.folder, touch.image)

    def image(self, touch):
        """The touch's frame as H x W x 3 uint8 RGB."""
        from PIL import Image
        path = self.image_path(touch)
        try:
            with Image.open(path) as im:
                return np.asarray(im.convert("RGB"), dtype=np.uint8).copy()
        except OSError as e:
            raise DatasetError(f"{path}: cannot read image ({e})") from None


@dataclass
class Dataset:
    root: str
    seed: int
    sensor: dict
    n_points: int
    objects: list            # DatasetObject, in dataset.json order

    def object(self, name):
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(name)


def _load_json(path):
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: missing")
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise DatasetError(f"{path}: not valid JSON ({e})") from None


def _field(d, key, path, kind):
    if not isinstance(d, dict) or key not in d:
        raise DatasetError(f"{path}: missing key {key!r}")
    v = d[key]
    ok = {"str": isinstance(v, str),
          "int": isinstance(v, int) and not isinstance(v, bool),
          "num": isinstance(v, (int, float)) and not isinstance(v, bool),
          "dict": isinstance(v, dict), "list": isinstance(v, list)}[kind]
    if not ok:
        raise DatasetError(f"{path}: key {key!r} has the wrong type")
    return v


def _read_csv(path, columns):
    """Rows of a CSV with a header holding at least ``columns`` (extra ones ignored)."""
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: missing")
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None:
            raise DatasetError(f"{path}: empty file (no header)")
        header = [h.strip() for h in header]
        missing = [c for c in columns if c not in header]
        if missing:
            raise DatasetError(f"{path}: missing columns {', '.join(missing)}")
        pos = {c: header.index(c) for c in columns}
        rows = []
        for line, row in enumerate(reader, start=2):
            if not row or all(not x.strip() for x in row):
                continue
            if len(row) != len(header):
                raise DatasetError(f"{path}:{line}: {len(row)} fields, header has {len(header)}")
            rows.append((line, {c: row[i].strip() for c, i in pos.items()}))
    return rows


def _num(row, cols, path, line, kind=float):
    try:
        return [kind(row[c]) for c in cols]
    except ValueError:
        bad = [c for c in cols if not _parses(row[c], kind)]
        raise DatasetError(f"{path}:{line}: column {bad[0]}: {row[bad[0]]!r} is not a number") from None


def _parses(text, kind):
    try:
        kind(text)
        return True
    except ValueError:
        return False


def read_points(path):
    rows = _read_csv(path, POINT_COLUMNS)
    if not rows:
        raise DatasetError(f"{path}: no points")
    return np.array([_num(r, POINT_COLUMNS, path, line) for line, r in rows], dtype=np.float64)


def read_touches(path, folder, check_images=True):
    touches = []
    for line, r in _read_csv(path, TOUCH_COLUMNS):
        (tid, order) = _num(r, ("id", "order"), path, line, int)
        if r["split"] not in SPLITS:
            raise DatasetError(f"{path}:{line}: split {r['split']!r} is not one of {', '.join(SPLITS)}")
        f = lambda cols: np.array(_num(r, cols, path, line), dtype=np.float64)
        t = Touch(id=tid, split=r["split"], order=order, image=r["image"],
                  contact=f(("cx", "cy", "cz")), normal=f(("nx", "ny", "nz")),
                  R=f(_R).reshape(3, 3), t=f(("tx", "ty", "tz")),
                  press_mm=float(f(("press_mm",))[0]), spin_deg=float(f(("spin_deg",))[0]),
                  tilt_deg=float(f(("tilt_deg",))[0]), motion=f(("dx", "dy", "dz")),
                  rel_R=f(_Q).reshape(3, 3), rel_t=f(("qx", "qy", "qz")))
        if check_images and not os.path.isfile(os.path.join(folder, t.image)):
            raise DatasetError(f"{path}:{line}: image {t.image} does not exist")
        touches.append(t)
    ids = [t.id for t in touches]
    if len(set(ids)) != len(ids):
        raise DatasetError(f"{path}: duplicate touch ids")
    touches.sort(key=lambda t: t.id)
    return touches


def read_object(root, entry, index, check_images=True):
    where = os.path.join(root, "dataset.json")
    name = _field(entry, "name", f"{where}: objects[{index}]", "str")
    folder = os.path.join(root, "objects", name)
    if not os.path.isdir(folder):
        raise DatasetError(f"{folder}: missing object folder (listed in {where})")
    oj_path = os.path.join(folder, "object.json")
    oj = _load_json(oj_path)
    subset = _field(entry, "subset", where, "str")
    osplit = _field(entry, "object_split", where, "str")
    if subset not in SUBSETS:
        raise DatasetError(f"{where}: object {name}: subset {subset!r} is not uniform/non-uniform")
    if osplit not in OBJECT_SPLITS:
        raise DatasetError(f"{where}: object {name}: object_split {osplit!r} is not seen/unseen")
    points_path = os.path.join(folder, "points.csv")
    points = read_points(points_path)
    n = _field(oj, "n_points", oj_path, "int")
    if n != len(points):
        raise DatasetError(f"{points_path}: {len(points)} points, object.json says {n}")
    touches = read_touches(os.path.join(folder, "touches.csv"), folder, check_images)
    obj = DatasetObject(
        name=name, folder=folder, subset=subset,
        dn_share=float(entry.get("dn_share", oj.get("dn_share", float("nan")))),
        object_split=osplit, scale_mm=float(_field(oj, "scale_mm", oj_path, "num")),
        diameter_mm=float(_field(oj, "diameter_mm", oj_path, "num")), n_points=n,
        sample_seed=int(oj.get("sample_seed", 0)), source=str(oj.get("source", "")),
        points=points, touches=touches)
    return obj


def read_dataset(root, check_images=True):
    """Read dataset.json and every object's json/csv files (images stay on disk)."""
    root = str(root)
    if not os.path.isdir(root):
        raise DatasetError(f"{root}: not a folder")
    path = os.path.join(root, "dataset.json")
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: missing (not a {FORMAT} dataset folder)")
    d = _load_json(path)
    fmt = d.get("format") if isinstance(d, dict) else None
    if fmt != FORMAT:
        raise DatasetError(f"{path}: format {fmt!r}, expected {FORMAT!r}")
    entries = _field(d, "objects", path, "list")
    objects = [read_object(root, e, i, check_images) for i, e in enumerate(entries)]
    names = [o.name for o in objects]
    if len(set(names)) != len(names):
        raise DatasetError(f"{path}: duplicate object names")
    return Dataset(root=root, seed=int(d.get("seed", 0)), sensor=dict(d.get("sensor", {})),
                   n_points=int(d.get("n_points", 0)), objects=objects)
