import json
import struct

import pytest
import torch

from weights_tools import safetensors_io as st


def _sample():
    return {
        "f32": torch.arange(6, dtype=torch.float32).reshape(2, 3) / 7,
        "f16": torch.tensor([1.5, -2.25], dtype=torch.float16),
        "bf16": torch.tensor([3.0, -0.5], dtype=torch.bfloat16),
        "f64": torch.tensor([1e-300, 3.5], dtype=torch.float64),
        "i64": torch.tensor(7, dtype=torch.int64),  # shape []
        "i32": torch.tensor([[-1, 2**31 - 1]], dtype=torch.int32),
        "u8": torch.tensor([0, 255], dtype=torch.uint8),
        "empty": torch.zeros(0, 3),
    }


def test_round_trip_bit_exact():
    data = _sample()
    out, meta = st.loads(st.dumps(data, {"k": "v"}))
    assert meta == {"k": "v"}
    assert set(out) == set(data)
    for k, v in data.items():
        assert out[k].dtype == v.dtype and out[k].shape == v.shape, k
        assert torch.equal(out[k], v), k


def test_header_layout():
    buf = st.dumps(_sample(), {"format": "pt"})
    (n,) = struct.unpack("<Q", buf[:8])
    assert n % 8 == 0
    text = buf[8:8 + n].decode()
    assert text == text.rstrip() + " " * (len(text) - len(text.rstrip()))
    header = json.loads(text)
    assert header.pop("__metadata__") == {"format": "pt"}
    spans = sorted(e["data_offsets"] for e in header.values())
    assert spans[0][0] == 0 and spans[-1][1] == len(buf) - 8 - n
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:]))
    assert header["i64"] == {"dtype": "I64", "shape": [], "data_offsets": header["i64"]["data_offsets"]}
    assert header["f32"]["dtype"] == "F32" and header["f32"]["shape"] == [2, 3]


def test_same_bytes_twice():
    assert st.dumps(_sample(), {"a": "b"}) == st.dumps(dict(reversed(list(_sample().items()))),
                                                      {"a": "b"})


def _file(header, data=b""):
    text = json.dumps(header).encode()
    return struct.pack("<Q", len(text)) + text + data


@pytest.mark.parametrize("header,data", [
    ({"a": {"dtype": "F32", "shape": [2], "data_offsets": [0, 4]}}, b"\0" * 4),   # size mismatch
    ({"a": {"dtype": "F32", "shape": [1], "data_offsets": [4, 8]}}, b"\0" * 8),   # gap
    ({"a": {"dtype": "F32", "shape": [1], "data_offsets": [0, 4]},
      "b": {"dtype": "F32", "shape": [1], "data_offsets": [0, 4]}}, b"\0" * 4),   # overlap
    ({"a": {"dtype": "Q8", "shape": [1], "data_offsets": [0, 1]}}, b"\0"),        # dtype
    ({"a": {"dtype": "U8", "shape": [1], "data_offsets": [0, 1]}}, b"\0\0"),      # trailing data
    ({"__metadata__": {"a": 1}}, b""),                                            # metadata
])
def test_rejects_malformed(header, data):
    with pytest.raises(st.FormatError):
        st.loads(_file(header, data))


def test_rejects_truncated():
    buf = st.dumps({"a": torch.ones(4)})
    with pytest.raises(st.FormatError):
        st.loads(buf[:-1])
    with pytest.raises(st.FormatError):
        st.loads(buf[:5])
