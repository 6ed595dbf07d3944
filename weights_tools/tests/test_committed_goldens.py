"""The committed goldens are what make_goldens produces, byte for byte."""

import os

import pytest

from weights_tools import make_goldens, safetensors_io

GOLDENS = make_goldens.DEFAULT_OUT


def test_regenerated_bytes_match(tmp_path):
    written = make_goldens.make_all(str(tmp_path))
    assert len(written) == 2 * len(make_goldens.CONFIGS) + 1 + len(make_goldens.SENSOR_GOLDENS)
    for path in written:
        name = os.path.basename(path)
        with open(path, "rb") as a, open(os.path.join(GOLDENS, name), "rb") as b:
            assert a.read() == b.read(), f"{name} differs: rerun python3 -m weights_tools.make_goldens"


def test_committed_goldens_are_small_and_valid():
    names = sorted(os.listdir(GOLDENS))
    sensor = make_goldens.SENSOR_CONFIG
    assert names == sorted([f"{c}{s}" for c in make_goldens.CONFIGS
                            for s in (".safetensors", ".golden.safetensors")]
                           + [f"{sensor}.safetensors"]
                           + [f"{sensor}.{label}.golden.safetensors"
                              for label, _ in make_goldens.SENSOR_GOLDENS])
    assert sum(os.path.getsize(os.path.join(GOLDENS, n)) for n in names) <= 2 * 1024 * 1024
    for n in names:
        _, meta = safetensors_io.load(os.path.join(GOLDENS, n))
        assert "vtloc.config" in meta


@pytest.mark.parametrize("name", make_goldens.CONFIGS)
def test_golden_refers_to_its_weights(name):
    import hashlib
    with open(os.path.join(GOLDENS, f"{name}.safetensors"), "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    _, meta = safetensors_io.load(os.path.join(GOLDENS, f"{name}.golden.safetensors"))
    assert meta["vtloc.golden.weights_sha256"] == digest


@pytest.mark.parametrize("label,mm", make_goldens.SENSOR_GOLDENS)
def test_sensor_goldens_rescale_the_frame(label, mm):
    import json
    from weights_tools import synthetic
    from weights_tools.tactile import rescaled_size
    t, meta = safetensors_io.load(os.path.join(GOLDENS, f"{make_goldens.SENSOR_CONFIG}.{label}.golden.safetensors"))
    cfg = json.loads(meta["vtloc.config"])
    assert cfg["sensor"] == {"mm_per_px": 0.1245, "height": 120, "width": 160}
    assert meta["vtloc.golden.mm_per_px"] == repr(mm)
    h, w = synthetic.tactile_image(0).shape[:2]
    assert tuple(t["input.tactile"].shape) == (h, w, 3)
    assert tuple(t["tactile.rescaled"].shape) == (rescaled_size(h, mm, 0.1245), rescaled_size(w, mm, 0.1245), 3)
