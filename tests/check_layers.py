#!/usr/bin/env python3
"""Fails when a source file includes a header of a layer above its own.

Every CMake target exports the project root, so the compiler cannot stop a
wrong-direction include; this check does (docs/architecture.md has the picture).

  python3 tests/check_layers.py [ROOT]     check the tree (default: this checkout)
  python3 tests/check_layers.py --self-test
"""
import os
import re
import sys
import tempfile

# layer -> the layers it may include (besides itself). Order is bottom-up.
ALLOWED = {
    "base": [],                                   # the error type every layer throws
    "shaders": ["base"],                          # SPIR-V registry (generated code)
    "runtime": ["base", "shaders"],               # Vulkan: device, memory, pipelines, recording
    "engine": ["base", "runtime"],                # tensors, graph, executor, weight files
    "engine/ops": ["base", "runtime", "engine"],  # one file per op + its CPU reference
    "engine/model": ["base", "runtime", "engine", "engine/ops"],  # VTLoc graph builders, runner
    "engine/track": ["base", "runtime", "engine", "engine/ops", "engine/model"],  # multi-touch filter
    "engine/check": ["base", "runtime", "engine", "engine/ops", "engine/model"],  # device self-test
    "engine/io": ["base", "engine"],              # files in and out (no Vulkan, no graph)
    "engine/sensor": ["base", "engine", "engine/io", "engine/ops"],  # ops: the gel ops' CPU mirrors  # GelSight model: calibration, gel shading, height field
    "engine/sim": ["base", "engine", "engine/io", "engine/model", "engine/sensor"],  # synthetic touches, datasets
    # The public API reaches the engine through the model layer (never a single op);
    # runtime only for device selection, engine/ only for tensors and dump files.
    "engine/api": ["base", "runtime", "engine", "engine/io", "engine/model", "engine/check", "engine/track", "engine/sensor"],
    "apps": ["base", "engine", "engine/io", "engine/sim", "engine/api", "engine/track", "engine/sensor"],
    "python": ["engine/api"],
}
# bench/ and tests/ may include anything: they measure and check single layers.
EXEMPT = ("bench", "tests")
SOURCES = (".h", ".cpp", ".in")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def layer_of(rel):
    """The layer owning a path relative to the root (None: not layered)."""
    rel = rel.replace(os.sep, "/")
    if rel.startswith("vtloc/"):  # the public header, <vtloc/vtloc.h>
        return "engine/api"
    best = None
    for layer in ALLOWED:
        if rel == layer or rel.startswith(layer + "/"):
            if best is None or len(layer) > len(best):
                best = layer
    return best


def violations(root):
    found = []
    for layer in ALLOWED:
        top = os.path.join(root, layer)
        if not os.path.isdir(top):
            continue
        for dirpath, _, files in os.walk(top):
            for f in sorted(files):
                if not f.endswith(SOURCES):
                    continue
                path = os.path.join(dirpath, f)
                rel = os.path.relpath(path, root)
                own = layer_of(rel)
                if own != layer:
                    continue  # a sub-layer's file: checked under its own layer
                with open(path, encoding="utf-8", errors="replace") as fh:
                    text = fh.read()
                for m in INCLUDE.finditer(text):
                    inc = m.group(1)
                    target = layer_of(inc) if "/" in inc else own
                    if target is None or target == own or target in ALLOWED[own]:
                        continue
                    line = text.count("\n", 0, m.start()) + 1
                    found.append(f"{rel}:{line}: {own} includes \"{inc}\" from {target}, "
                                 f"which {own} may not use (allowed: {', '.join(ALLOWED[own]) or 'nothing'})")
    return found


def self_test():
    """The check must catch a wrong include and pass a right one."""
    with tempfile.TemporaryDirectory() as d:
        os.makedirs(os.path.join(d, "runtime"))
        os.makedirs(os.path.join(d, "engine", "ops"))
        with open(os.path.join(d, "engine", "ops", "good.cpp"), "w") as f:
            f.write('#include "runtime/context.h"\n#include "engine/graph.h"\n#include "local.h"\n')
        assert violations(d) == [], violations(d)
        with open(os.path.join(d, "runtime", "bad.cpp"), "w") as f:
            f.write('#include <vector>\n#include "engine/model/gma.h"\n')
        v = violations(d)
        assert len(v) == 1 and "runtime/bad.cpp:2" in v[0] and "engine/model" in v[0], v
    print("self-test: a wrong-direction include is caught, right ones pass")


def main():
    if sys.argv[1:] == ["--self-test"]:
        self_test()
        return 0
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    v = violations(root)
    for line in v:
        print(line)
    if v:
        print(f"{len(v)} wrong-direction include(s); see docs/architecture.md for the layers")
        return 1
    print("every include points down (docs/architecture.md)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
