"""The CTest copies of test cases meant for subgroup size 4 (tests/CMakeLists.txt:
names sg4/... and long/sg4/...) each set LP_NATIVE_VECTOR_WIDTH=128, and each
prefix holds as many tests as its Catch specs list. A lost variable once made
the sg4/ tests repeat the subgroup-8 run unnoticed; the binary's own guard
("the subgroup-4 run sees subgroup size 4") checks only that lavapipe honours
the variable where it is set, and runs under sg4/ alone.
  check_subgroup_runs.py CTEST BUILD_DIR TEST_BINARY PREFIX=SPEC[|SPEC..] ...
  check_subgroup_runs.py --self-test     (the check fails on a lost variable)"""

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


def problems(tests, expected):
    """tests: ctest --show-only=json-v1's "tests"; expected: {prefix: count}.
    A name goes to the longest prefix it starts with."""
    out, counts = [], {p: 0 for p in expected}
    for t in tests:
        hits = [p for p in expected if t["name"].startswith(p)]
        if not hits:
            continue
        prefix = max(hits, key=len)
        counts[prefix] += 1
        if VAR not in environment(t):
            out.append(f"{t['name']}: environment {environment(t)} lacks {VAR}")
    for p, n in expected.items():
        if counts[p] != n:
            out.append(f"{p}: {counts[p]} CTest tests, but its specs list {n} test cases")
    return out


def listed(binary, spec):
    # Catch 2's listing exits with the number of cases it lists: its output counts.
    r = subprocess.run([binary, "--list-test-names-only", spec], capture_output=True, text=True)
    return [line for line in r.stdout.splitlines() if line.strip()]


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
    assert problems([good, other], {"sg4/": 1, "long/sg4/": 0}) == []
    found = problems([good, lost, other], {"sg4/": 1, "long/sg4/": 1})
    assert len(found) == 1 and "long/sg4/b" in found[0], found
    found = problems([good], {"sg4/": 2, "long/sg4/": 0})
    assert len(found) == 1 and "1 CTest tests" in found[0], found
    print("self-test: a lost variable and a short discovery are both caught")
    return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    ctest, build, binary, groups = argv[1], argv[2], argv[3], argv[4:]
    expected = {}
    for g in groups:
        prefix, specs = g.split("=", 1)
        expected[prefix] = sum(len(listed(binary, s)) for s in specs.split("|"))
        if expected[prefix] == 0:
            print(f"{prefix}: its specs {specs} list no test case", file=sys.stderr)
            return 1
    found = problems(shown_tests(ctest, build), expected)
    for p in found:
        print(p, file=sys.stderr)
    if not found:
        print(", ".join(f"{p}: {n} tests, each with {VAR}" for p, n in expected.items()))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
