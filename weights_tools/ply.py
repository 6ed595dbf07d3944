"""PLY point clouds and meshes: read the vertex element, or vertices and triangles
(ascii / binary, either endianness); write binary little-endian x y z nx ny nz."""

import numpy as np

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def _parse_header(f):
    if f.readline().strip() != b"ply":
        raise ValueError("not a PLY file")
    fmt, elements = None, []
    while True:
        line = f.readline()
        if not line:
            raise ValueError("PLY header without end_header")
        words = line.decode("ascii", "replace").split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "end_header":
            return fmt, elements
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            if words[1] == "list":  # (name, count type, item type)
                elements[-1][2].append((words[4], ("list", _TYPES[words[2]], _TYPES[words[3]])))
            else:
                elements[-1][2].append((words[2], _TYPES[words[1]]))


def _skip_binary(f, count, props, endian):
    """Skip an element we do not need (may hold list properties, e.g. faces)."""
    if all(not isinstance(t, tuple) for _, t in props):
        f.read(count * sum(np.dtype(t).itemsize for _, t in props))
        return
    for _ in range(count):
        for _, t in props:
            if isinstance(t, tuple):
                n = int(np.frombuffer(f.read(np.dtype(t[1]).itemsize), endian + t[1])[0])
                f.read(n * np.dtype(t[2]).itemsize)
            else:
                f.read(np.dtype(t).itemsize)


def _header_and_endian(f):
    """(format, elements, '<' / '>' or None for ascii) of an open file, its header read."""
    fmt, elements = _parse_header(f)
    endian = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
    if fmt != "ascii" and endian is None:
        raise ValueError(f"unsupported PLY format {fmt!r}")
    return fmt, elements, endian


def read_ply(path):
    """Return an N x 3 or N x 6 float32 array: x y z, plus nx ny nz when present."""
    with open(path, "rb") as f:
        fmt, elements, endian = _header_and_endian(f)
        ascii_lines = f.read().decode("ascii").splitlines() if fmt == "ascii" else None
        row = 0
        for name, count, props in elements:
            if name != "vertex":
                if ascii_lines is not None:
                    row += count
                else:
                    _skip_binary(f, count, props, endian)
                continue
            if any(isinstance(t, tuple) for _, t in props):
                raise ValueError("list properties in the vertex element are not supported")
            names = [p for p, _ in props]
            if ascii_lines is not None:
                rows = [ln.split() for ln in ascii_lines[row:row + count]]
                data = {p: np.array([float(r[i]) for r in rows]) for i, p in enumerate(names)}
            else:
                dt = np.dtype([(p, endian + t) for p, t in props])
                arr = np.frombuffer(f.read(count * dt.itemsize), dtype=dt, count=count)
                data = {p: arr[p].astype(np.float64) for p in names}
            cols = ["x", "y", "z"]
            if not all(c in data for c in cols):
                raise ValueError("PLY vertices need x, y, z")
            if all(c in data for c in ("nx", "ny", "nz")):
                cols += ["nx", "ny", "nz"]
            return np.stack([data[c] for c in cols], axis=1).astype(np.float32)
    raise ValueError("PLY file has no vertex element")


def _read_exact(f, n):
    b = f.read(n)
    if len(b) != n:
        raise EOFError
    return b


def _read_rows_binary(f, count, props, endian):
    """An element with list properties -> {name: values (rows of int arrays for lists)}: at once
    where every list holds 3 items (a triangle mesh's faces), else row by row."""
    fields = []
    for p, t in props:
        fields += [(p + "#n", endian + t[1]), (p, endian + t[2], (3,))] if isinstance(t, tuple) else [(p, endian + t)]
    dt, start = np.dtype(fields), f.tell()
    buf = f.read(count * dt.itemsize)
    if len(buf) == count * dt.itemsize:
        arr = np.frombuffer(buf, dtype=dt)
        if all(np.all(arr[p + "#n"] == 3) for p, t in props if isinstance(t, tuple)):
            return {p: arr[p] for p, _ in props}
    f.seek(start)
    cols = {p: [] for p, _ in props}
    for _ in range(count):
        for p, t in props:
            if isinstance(t, tuple):
                n = int(np.frombuffer(_read_exact(f, np.dtype(t[1]).itemsize), endian + t[1])[0])
                cols[p].append(np.frombuffer(_read_exact(f, n * np.dtype(t[2]).itemsize), endian + t[2], count=n))
            else:
                cols[p].append(np.frombuffer(_read_exact(f, np.dtype(t).itemsize), endian + t)[0])
    return cols


def read_ply_triangles(path):
    """Return (V, T) of a triangle mesh: V an N x 3 float64 array of x y z, T an M x 3 int64
    array of vertex indices. ValueError naming the file for a file that is not a PLY mesh, data
    that ends early or is not numbers, a face that is not a triangle or an index out of range."""
    try:
        return _read_triangles(path)
    except (StopIteration, EOFError):
        raise ValueError(f"{path}: the PLY data ends before the header's counts do") from None
    except ValueError as e:
        if str(e).startswith(f"{path}:"):
            raise
        raise ValueError(f"{path}: {e}") from None


def _read_triangles(path):
    with open(path, "rb") as f:
        fmt, elements, endian = _header_and_endian(f)
        tokens = iter(f.read().decode("ascii").split()) if fmt == "ascii" else None
        V = faces = None
        for name, count, props in elements:
            if tokens is not None:  # ascii: one row per element, lists as count then items
                cols = {p: [] for p, _ in props}
                for _ in range(count):
                    for p, t in props:
                        if isinstance(t, tuple):
                            n = int(next(tokens))
                            cols[p].append(np.array([int(next(tokens)) for _ in range(n)], np.int64))
                        else:
                            cols[p].append(float(next(tokens)))
            elif all(not isinstance(t, tuple) for _, t in props):
                dt = np.dtype([(p, endian + t) for p, t in props])
                arr = np.frombuffer(_read_exact(f, count * dt.itemsize), dtype=dt, count=count)
                cols = {p: arr[p] for p, _ in props}
            elif name == "face":
                cols = _read_rows_binary(f, count, props, endian)
            else:
                _skip_binary(f, count, props, endian)
                continue
            if name == "vertex":
                if not all(c in cols for c in "xyz"):
                    raise ValueError(f"{path}: PLY vertices need x, y, z")
                V = np.stack([np.asarray(cols[c], np.float64) for c in "xyz"], axis=1).reshape(count, 3)
            elif name == "face":
                lists = next((cols[p] for p, t in props if isinstance(t, tuple)), None)
                if lists is None:
                    raise ValueError(f"{path}: the face element has no list of vertex indices")
                if any(len(r) != 3 for r in lists):
                    raise ValueError(f"{path}: faces must be triangles")
                faces = np.array(lists, np.int64).reshape(count, 3)
    if V is None or faces is None:
        raise ValueError(f"{path}: a mesh needs a vertex and a face element")
    if faces.size and (faces.min() < 0 or faces.max() >= len(V)):
        raise ValueError(f"{path}: a face names a vertex out of range (0..{len(V) - 1})")
    return V, faces


def write_ply(path, points):
    """points: N x 3 or N x 6 (xyz [+ normals]) -> binary little-endian PLY."""
    pts = np.ascontiguousarray(points, dtype="<f4")
    names = ["x", "y", "z", "nx", "ny", "nz"][:pts.shape[1]]
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {len(pts)}"]
    head += [f"property float {n}" for n in names] + ["end_header", ""]
    with open(path, "wb") as f:
        f.write("\n".join(head).encode("ascii"))
        f.write(pts.tobytes())
