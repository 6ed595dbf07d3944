"""vtloc-bench --vs-pytorch: the report holds the host CPU, the PyTorch
reference's times (end to end and per stage, its threads and BLAS) and the
engine/PyTorch ratios, each positive.  No timing is asserted."""

import json
import sys

rep = json.load(open(sys.argv[1]))
host = rep["host"]
assert host["cpu"] and host["cores"] >= 1 and isinstance(host["simd"], list), host
t = rep["pytorch"]
assert t["tool"] == "weights_tools.bench_torch" and t["dtype"] == "float32" and t["threads"] >= 1, t
assert t["blas"]["built_with"] and t["blas"]["loaded"], t["blas"]
assert t["end_to_end_ms"]["median"] > 0 and t["points"] == rep["inputs"]["points"]
assert set(t["stages_ms"]) == {"preprocess", "tactile", "point", "heads", "retrieval"}, t["stages_ms"]
r = rep["engine_over_pytorch"]
for k in ("end_to_end", "stage tactile", "stage point", "stage gma + head", "stage retrieval"):
    assert r[k] > 0, (k, r)
print("ok:", {k: round(v, 3) for k, v in r.items()})
