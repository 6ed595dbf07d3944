"""Fixtures of the vtloc module's tests: run by CTest (python.pytest) with
PYTHONPATH at build/python, VTLOC_CLI at the built CLI and the validation
layer on (VTLOC_VALIDATION=1); every context must end with no message."""

import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)  # weights_tools.safetensors_io reads the CLI's dumps

import vtloc  # noqa: E402


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("VTLOC_CLI", os.path.join(ROOT, "build", "vtloc"))
    if not os.path.exists(path):
        pytest.fail(f"{path}: the vtloc CLI is not built (set VTLOC_CLI)")
    return path


@pytest.fixture(scope="session")
def ctx():
    c = vtloc.Context()
    yield c
    assert c.take_validation_messages() == []


@pytest.fixture(scope="session")
def tiny_path():
    return os.path.join(ROOT, "weights_tools", "goldens", "vtloc-tiny.safetensors")


@pytest.fixture(scope="session")
def tiny(ctx, tiny_path):
    return vtloc.Model(ctx, tiny_path)


@pytest.fixture(scope="session")
def mug(tiny):
    return tiny.encode_object(os.path.join(ROOT, "examples", "mug.glb"))


@pytest.fixture(scope="session")
def touch(root):
    return os.path.join(root, "examples", "touch_01.png")
