"""vtloc-bench --vs-pytorch: the report holds the host CPU, the PyTorch
reference's times (end to end and per stage, its threads and BLAS) and the
engine/PyTorch ratios, each positive, and where retrieval runs in the ILU's
dispatch, the split that times it.  No timing is asserted."""

import json
import sys

rep = json.load(open(sys.argv[1]))
host = rep["host"]
assert host["cpu"] and host["cores"] >= 1 and isinstance(host["simd"], list), host
t = rep["pytorch"]
assert t["tool"] == "weights_tools.bench_torch" and t["dtype"] == "float32" and t["threads"] >= 1, t
assert t["device"] == "cpu", t  # the default: --pytorch-device cuda is for a GPU machine
assert t["blas"]["built_with"] and t["blas"]["loaded"], t["blas"]
assert t["end_to_end_ms"]["median"] > 0 and t["points"] == rep["inputs"]["points"]
assert set(t["stages_ms"]) == {"preprocess", "tactile", "point", "heads", "retrieval"}, t["stages_ms"]
r = rep["engine_over_pytorch"]
for k in ("end_to_end", "end_to_end_fastest", "stage tactile", "stage point", "stage gma + head"):
    assert r[k] > 0, (k, r)
fastest = rep["gpu"]["end_to_end_ms"]["min"] / t["end_to_end_ms"]["min"]
assert abs(r["end_to_end_fastest"] - fastest) <= 1e-12 * fastest, (r["end_to_end_fastest"], fastest)
# Retrieval runs in the ILU's dispatch: its ratio is what it adds there, which
# timing noise can hide on a model this small (then the split is reported and
# the ratio left out); a retrieval node of its own must have its ratio.
if "retrieval" in rep["gpu"]["stages_ms"]:
    assert r["stage retrieval"] > 0, r
else:
    s = rep["gpu"]["retrieval_split"]
    assert s["fused_head_ms"] > 0 and s["head_alone_ms"] > 0 and s["node_ms"] > 0, s
    assert abs(s["epilogue_ms"] - (s["fused_head_ms"] - s["head_alone_ms"])) < 1e-9, s
    assert ("stage retrieval" in r) == (s["epilogue_ms"] > 0), (s, r)
print("ok:", {k: round(v, 3) for k, v in r.items()})
