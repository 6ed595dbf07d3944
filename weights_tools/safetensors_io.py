"""Minimal safetensors reader/writer (no dependency on the safetensors package).

Layout: u64 little-endian header length, JSON header (space padded to a multiple
of 8 bytes), then the data area.  Tensors are written in name order, back to
back, so the same dict always gives the same bytes.
"""

import json
import struct

import numpy as np
import torch

# safetensors dtype -> (numpy little-endian dtype, torch dtype)
_DTYPES = {
    "F64": ("<f8", torch.float64),
    "F32": ("<f4", torch.float32),
    "F16": ("<f2", torch.float16),
    "BF16": ("<i2", torch.bfloat16),  # numpy has no bfloat16: carry the raw bits
    "I64": ("<i8", torch.int64),
    "I32": ("<i4", torch.int32),
    "I16": ("<i2", torch.int16),
    "I8": ("i1", torch.int8),
    "U8": ("u1", torch.uint8),
    "BOOL": ("?", torch.bool),
}
_BY_TORCH = {t: name for name, (_, t) in _DTYPES.items()}

MAX_HEADER = 100 * 1024 * 1024


class FormatError(ValueError):
    pass


def _raw(t):
    """Little-endian bytes of a tensor (torch or numpy) and its safetensors dtype."""
    if isinstance(t, np.ndarray):
        t = torch.from_numpy(np.ascontiguousarray(t))
    if not isinstance(t, torch.Tensor):
        raise TypeError(f"not a tensor: {type(t)}")
    t = t.detach().cpu().contiguous()
    if t.dtype not in _BY_TORCH:
        raise TypeError(f"unsupported dtype {t.dtype}")
    name = _BY_TORCH[t.dtype]
    if t.dtype == torch.bfloat16:
        arr = t.view(torch.int16).numpy().astype("<i2", copy=False)
    else:
        arr = t.numpy().astype(_DTYPES[name][0], copy=False)
    return name, list(t.shape), arr.tobytes()


def dumps(tensors, metadata=None):
    """Serialise {name: tensor} (+ str->str metadata) to bytes."""
    header = {}
    if metadata:
        if not all(isinstance(k, str) and isinstance(v, str) for k, v in metadata.items()):
            raise TypeError("metadata must map str to str")
        header["__metadata__"] = dict(sorted(metadata.items()))
    chunks, offset = [], 0
    for name in sorted(tensors):
        if name == "__metadata__":
            raise ValueError("reserved tensor name")
        dtype, shape, data = _raw(tensors[name])
        header[name] = {"dtype": dtype, "shape": shape,
                        "data_offsets": [offset, offset + len(data)]}
        chunks.append(data)
        offset += len(data)
    text = json.dumps(header, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 8)
    return struct.pack("<Q", len(text)) + text + b"".join(chunks)


def save(path, tensors, metadata=None):
    with open(path, "wb") as f:
        f.write(dumps(tensors, metadata))


def parse_header(buf):
    """Validate the header of a whole file's bytes; return (entries, metadata, data_start)."""
    if len(buf) < 8:
        raise FormatError("file shorter than 8 bytes")
    (n,) = struct.unpack("<Q", buf[:8])
    if n > MAX_HEADER or 8 + n > len(buf):
        raise FormatError(f"header length {n} exceeds the file")
    try:
        header = json.loads(buf[8:8 + n].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise FormatError(f"header is not JSON: {e}") from None
    if not isinstance(header, dict):
        raise FormatError("header is not a JSON object")
    meta = header.pop("__metadata__", None) or {}
    if not isinstance(meta, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in meta.items()):
        raise FormatError("__metadata__ must map str to str")
    data_len = len(buf) - 8 - n
    spans = []
    for name, e in header.items():
        if not isinstance(e, dict) or set(e) != {"dtype", "shape", "data_offsets"}:
            raise FormatError(f"{name}: bad entry {e!r}")
        if e["dtype"] not in _DTYPES:
            raise FormatError(f"{name}: unknown dtype {e['dtype']!r}")
        shape, offs = e["shape"], e["data_offsets"]
        if not isinstance(shape, list) or not all(
                isinstance(d, int) and not isinstance(d, bool) and d >= 0 for d in shape):
            raise FormatError(f"{name}: bad shape {shape!r}")
        if not (isinstance(offs, list) and len(offs) == 2 and all(
                isinstance(o, int) and not isinstance(o, bool) for o in offs)):
            raise FormatError(f"{name}: bad data_offsets {offs!r}")
        count = int(np.prod(shape, dtype=np.int64)) if shape else 1
        size = count * np.dtype(_DTYPES[e["dtype"]][0]).itemsize
        if offs[1] - offs[0] != size or offs[0] < 0:
            raise FormatError(f"{name}: data_offsets {offs} do not hold {size} bytes")
        spans.append((offs[0], offs[1], name))
    spans.sort()
    pos = 0
    for begin, end, name in spans:
        if begin != pos:
            raise FormatError(f"{name}: gap or overlap at byte {begin} (expected {pos})")
        pos = end
    if pos != data_len:
        raise FormatError(f"data area is {data_len} bytes, tensors cover {pos}")
    return header, meta, 8 + n


def loads(buf):
    """Parse bytes; return ({name: torch tensor}, metadata)."""
    header, meta, start = parse_header(buf)
    out = {}
    for name, e in header.items():
        b, end = e["data_offsets"]
        np_dtype, t_dtype = _DTYPES[e["dtype"]]
        arr = np.frombuffer(buf, dtype=np_dtype, count=(end - b) // np.dtype(np_dtype).itemsize,
                            offset=start + b)
        # copy into native byte order: torch needs writable, native arrays
        t = torch.from_numpy(arr.astype(arr.dtype.newbyteorder("="), copy=True))
        if t_dtype == torch.bfloat16:
            t = t.view(torch.int16).view(torch.bfloat16)
        out[name] = t.reshape(e["shape"])
    return out, meta


def load(path):
    with open(path, "rb") as f:
        return loads(f.read())
