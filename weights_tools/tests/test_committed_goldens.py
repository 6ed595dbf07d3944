"""The committed goldens are what make_goldens produces, byte for byte."""

import os

import pytest

from weights_tools import make_goldens, safetensors_io

GOLDENS = make_goldens.DEFAULT_OUT


def test_regenerated_bytes_match(tmp_path):
    written = make_goldens.make_all(str(tmp_path))
    assert len(written) == 2 * len(make_goldens.CONFIGS)
    for path in written:
        name = os.path.basename(path)
        with open(path, "rb") as a, open(os.path.join(GOLDENS, name), "rb") as b:
            assert a.read() == b.read(), f"{name} differs: rerun python3 -m weights_tools.make_goldens"


def test_committed_goldens_are_small_and_valid():
    names = sorted(os.listdir(GOLDENS))
    assert names == sorted(f"{c}{s}" for c in make_goldens.CONFIGS
                           for s in (".safetensors", ".golden.safetensors"))
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
