"""The CTest tests that run test cases at subgroup size 4 (tests/CMakeLists.txt:
names sg4/... and long/sg4/..., one per source file) each set
LP_NATIVE_VECTOR_WIDTH=128 (and no other test does), and each prefix's tests
together run every case its Catch specs list, once (cpp/, golden/ and long/ too). A lost variable once made
the sg4/ tests repeat the subgroup-8 run unnoticed; the binary's own guard
("the subgroup-4 run sees subgroup size 4") checks only that lavapipe honours
the variable where it is set, and runs under sg4/ alone.
  check_shards.py CTEST BUILD_DIR TEST_BINARY PREFIX=SPEC[|SPEC..] ...
  check_shards.py --self-test     (the check fails on a lost variable)"""

import json
import os
import shutil
import subprocess
import sys
import tempfile

VAR = "LP_NATIVE_VECTOR_WIDTH=128"


def environment(test):
    for p in test.get("properties", []):
        if p["name"] == "ENVIRONMENT":
            return list(p["value"])
    return []


def problems(tests, expected, runs):
    """tests: ctest --show-only=json-v1's "tests"; expected: {prefix: set of case names};
    runs(test): the case names a test runs. A name goes to the longest prefix it starts with."""
    out, got = [], {p: [] for p in expected}
    for t in tests:
        hits = [p for p in expected if t["name"].startswith(p)]
        if not hits:
            continue
        prefix = max(hits, key=len)
        got[prefix] += runs(t)
        wants = "sg4/" in prefix  # the other prefixes run at the device's own width
        if wants != (VAR in environment(t)):
            out.append(f"{t['name']}: environment {environment(t)} " + ("lacks " if wants else "has ") + VAR)
    for p, want in expected.items():
        have = got[p]
        if len(have) != len(set(have)):
            out.append(f"{p}: {len(have) - len(set(have))} test cases run twice")
        if set(have) != want:
            miss = sorted(want - set(have))
            out.append(f"{p}: its tests run {len(set(have))} test cases, its specs list {len(want)}"
                       + (f" (missing: {miss[0]!r}...)" if miss else ""))
    return out


def listed(binary, spec, by_file=False):
    # Catch 2's listing exits with the number of cases it lists: its output counts.
    r = subprocess.run([binary] + (["-#"] if by_file else []) + ["--list-test-names-only", spec],
                       capture_output=True, text=True)
    return [line for line in r.stdout.splitlines() if line.strip()]


def runs(test):
    """The cases a sharded test runs: its command is BINARY -# SPEC -w NoTests."""
    cmd = test.get("command", [])
    if len(cmd) < 3 or cmd[1] != "-#":
        return []
    return listed(cmd[0], cmd[2], by_file=True)


def shown_tests(ctest, build):
    # ctest rewrites BUILD/Testing/Temporary/LastTest.log even for --show-only, and the
    # ctest run this check is part of is writing that log: read a copy of the test files
    # (the discovered tests' scripts are included by absolute path, so they need no copy).
    with tempfile.TemporaryDirectory() as tmp:
        for here, dirs, files in os.walk(build):
            dirs[:] = [d for d in dirs if d not in ("CMakeFiles", "Testing")]
            if "CTestTestfile.cmake" in files:
                there = os.path.join(tmp, os.path.relpath(here, build))
                os.makedirs(there, exist_ok=True)
                shutil.copy(os.path.join(here, "CTestTestfile.cmake"), there)
        shown = subprocess.run([ctest, "--test-dir", tmp, "--show-only=json-v1"], capture_output=True, text=True,
                               check=True)
    return json.loads(shown.stdout)["tests"]


def self_test():
    good = {"name": "sg4/a", "properties": [{"name": "ENVIRONMENT", "value": [VAR]}]}
    lost = {"name": "long/sg4/b", "properties": [{"name": "LABELS", "value": ["long"]}]}
    other = {"name": "long/c", "properties": []}
    cases = {"sg4/a": ["x", "y"], "long/sg4/b": ["z"], "long/c": ["z"]}
    run = lambda t: cases[t["name"]]
    assert problems([good, other], {"sg4/": {"x", "y"}, "long/sg4/": set()}, run) == []
    found = problems([good, lost, other], {"sg4/": {"x", "y"}, "long/sg4/": {"z"}}, run)
    assert len(found) == 1 and "long/sg4/b" in found[0], found
    found = problems([good], {"sg4/": {"x", "y", "w"}, "long/sg4/": set()}, run)
    assert len(found) == 1 and "run 2 test cases" in found[0] and "'w'" in found[0], found
    found = problems([good, dict(good)], {"sg4/": {"x", "y"}, "long/sg4/": set()}, run)
    assert len(found) == 1 and "run twice" in found[0], found
    narrow = {"name": "long/c", "properties": [{"name": "ENVIRONMENT", "value": [VAR]}]}
    found = problems([good, narrow], {"sg4/": {"x", "y"}, "long/": {"z"}}, run)
    assert len(found) == 1 and "long/c" in found[0] and "has" in found[0], found
    print("self-test: a lost or stray variable, a missing case and a case run twice are all caught")
    return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    ctest, build, binary, groups = argv[1], argv[2], argv[3], argv[4:]
    expected = {}
    for g in groups:
        prefix, specs = g.split("=", 1)
        expected[prefix] = {n for s in specs.split("|") for n in listed(binary, s)}
        if not expected[prefix]:
            print(f"{prefix}: its specs {specs} list no test case", file=sys.stderr)
            return 1
    found = problems(shown_tests(ctest, build), expected, runs)
    for p in found:
        print(p, file=sys.stderr)
    if not found:
        print(", ".join(f"{p}: {len(n)} test cases" for p, n in expected.items()) + f"; {VAR} on sg4/ only")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
