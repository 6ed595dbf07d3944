"""Checks a vtloc-bench JSON report's schema (bench/README.md) and plot.

  python3 check_bench_json.py REPORT.json PLOT.png REPS ITERS BATCHES POINTS TRACKER_WINDOW

Asserts structure, types and internal consistency (counts, which N / batch /
point sizes were measured, positive times and sizes), never speed.
"""

import json
import math
import sys

STAGES = {"preprocess", "tactile", "point", "gma", "head", "retrieval", "other", "total"}


def fail(msg):
    sys.exit(f"check_bench_json: {msg}")


def need(cond, msg):
    if not cond:
        fail(msg)


def positive(x, what):
    need(isinstance(x, (int, float)) and math.isfinite(x) and x > 0, f"{what} must be a positive number, got {x!r}")


def stats(s, what, n):
    need(isinstance(s, dict), f"{what} must be a stats object, got {s!r}")
    need(set(s) == {"median", "p10", "p90", "min", "n"}, f"{what} keys {sorted(s)}")
    need(s["n"] == n, f"{what}: n = {s['n']}, expected {n}")
    for k in ("median", "p10", "p90", "min"):
        positive(s[k], f"{what}.{k}")
    need(s["min"] <= s["p10"] <= s["median"] <= s["p90"] + 1e-12, f"{what}: quantiles out of order {s}")


def backend(b, name, reps, profile_reps, iters, batches, points, ilu):
    stats(b["end_to_end_ms"], f"{name}.end_to_end_ms", reps)
    stats(b["cached_touch_ms"], f"{name}.cached_touch_ms", reps)
    positive(b["first_run_ms"], f"{name}.first_run_ms")
    st = b["stages_ms"]
    need(set(st) <= STAGES and {"tactile", "point", "head", "total"} <= set(st), f"{name} stages {sorted(st)}")
    for k, v in st.items():
        stats(v, f"{name}.stages_ms.{k}", profile_reps)
    parts = sum(v["median"] for k, v in st.items() if k != "total")
    need(parts >= st["total"]["p10"] * 0.5, f"{name}: stage medians {parts} vs total {st['total']}")
    need(len(b["nodes"]) > 10, f"{name}: only {len(b['nodes'])} nodes")
    for n in b["nodes"]:
        need(n["stage"] in STAGES and n["name"] and n["op"], f"{name}: bad node {n}")
        need(n["ms"] >= 0, f"{name}: negative node time {n}")
        if "workgroups" in n:  # the GPU's dispatches of the node, each's workgroup count
            need(name == "gpu" and n["workgroups"] and all(isinstance(w, int) and w >= 1 for w in n["workgroups"]),
                 f"{name}: bad workgroups {n}")
    if name == "gpu":  # nearly every node dispatches (a few are views or copies)
        need(sum("workgroups" in n for n in b["nodes"]) >= 0.8 * len(b["nodes"]), f"{name}: workgroups missing on most nodes")
    for k in ("conv", "mlp"):
        e = b["efficiency"][k]
        for f in ("gflop", "ms", "gflops", "fastest_ms", "gflops_fastest"):
            positive(e[f], f"{name}.efficiency.{k}.{f}")
        # each node's fastest run, summed, can never exceed the median of the run sums
        need(e["fastest_ms"] <= e["ms"] * (1 + 1e-12), f"{name}.efficiency.{k}: fastest {e['fastest_ms']} > median {e['ms']}")
    need([r["batch"] for r in b["batch"]] == batches, f"{name}: batches {b['batch']}")
    for r in b["batch"]:
        stats(r["ms"], f"{name}.batch{r['batch']}", reps)
        need(abs(r["touches_per_s"] - 1e3 * r["batch"] / r["ms"]["median"]) < 1e-6 * r["touches_per_s"],
             f"{name}: touches/s inconsistent {r}")
    if ilu:
        t = b["ilu"]["table"]
        need([r["n"] for r in t] == iters, f"{name}: ILU sweep N {[r['n'] for r in t]}")
        for r in t:
            stats(r["end_to_end_ms"], f"{name}.ilu N={r['n']}", reps)
            positive(r["ilu_gpu_ms"], f"{name}.ilu N={r['n']} node")
            need((r["ms_per_iter"] is None) == (r["n"] == 0), f"{name}: ms_per_iter {r}")
        for k in ("end_to_end", "ilu_node"):
            need(math.isfinite(b["ilu"]["slope_ms_per_iter"][k]), f"{name}: slope {k}")
    need([r["points"] for r in b.get("points", [])] == points, f"{name}: point sweep {b.get('points')}")
    for r in b.get("points", []):
        stats(r["encode_ms"], f"{name}.points {r['points']}", reps)
        for k in ("node_sum_ms", "fps_ms", "ball_query_ms"):
            positive(r[k], f"{name}.points {r['points']}.{k}")
        need(r["fps_ms"] + r["ball_query_ms"] <= r["node_sum_ms"] * 1.0001, f"{name}: point shares {r}")


def main(path, plot, reps, iters, batches, points, window):
    r = json.load(open(path))
    need(r["schema"] == "vtloc-bench/1", f"schema {r.get('schema')}")
    need(len(r["date"]) == 10, "date")
    for k in ("name", "type", "driver_version", "subgroup_size"):
        need(k in r["device"], f"device.{k}")
    positive(r["model"]["parameters"], "model.parameters")
    need(abs(r["model"]["mib_fp32"] - r["model"]["parameters"] * 4 / 2**20) < 1e-9, "model.mib_fp32")
    positive(r["inputs"]["points"], "inputs.points")
    s = r["settings"]
    need(s["reps"] == reps and s["iters"] == iters and s["batch"] == batches and s["points"] == points,
         f"settings {s}")
    p = r["probe"]
    for k in ("gflops", "before", "after", "dispatch_overhead_us"):
        positive(p[k], f"probe.{k}")
    need(p["gflops"] == max(p["before"], p["after"]), "probe.gflops is the higher of before/after")
    g = r["gpu"]
    ilu = "ilu" in g
    backend(g, "gpu", reps, s["profile_reps"], iters, batches, points, ilu)
    m = g["memory"]
    for k in ("weights_bytes", "activations_peak_bytes", "total_bytes"):
        positive(m[k], f"memory.{k}")
    need(m["total_bytes"] == m["weights_bytes"] + m["activations_peak_bytes"], "memory.total_bytes")
    need(m["activations_peak_bytes"] <= m["activations_unplanned_bytes"], "arena above one-buffer-per-tensor")
    a = g["memory_all_shapes"]
    need(a["graphs"] > 1, "memory_all_shapes: the run built several graph shapes")
    # Weights are held once: no more than the largest graph reads (+ alignment), far below one copy per graph.
    need(a["weights_resident_bytes"] <= m["weights_bytes"] + 4096, "memory_all_shapes: weights resident once")
    need(a["weights_if_per_graph_bytes"] >= a["graphs"] // 2 * m["weights_bytes"] // 2,
         "memory_all_shapes: per-graph weight sum")
    for k in ("conv", "mlp"):
        f = g["efficiency"][k]["fraction_of_peak"]
        need(abs(f - g["efficiency"][k]["gflops"] / p["gflops"]) < 1e-9, f"fraction_of_peak {k}")
        f = g["efficiency"][k]["fraction_of_peak_fastest"]
        need(abs(f - g["efficiency"][k]["gflops_fastest"] / p["gflops"]) < 1e-9, f"fraction_of_peak_fastest {k}")
    stats(g["end_to_end_late_ms"], "gpu.end_to_end_late_ms", reps)  # the same timing after the rest
    # The executor's node orders in turns: 3 rounds of max(1, reps // 2) each; steps and
    # late share barriers between independent nodes, so they record fewer than serial.
    sc = g["schedules"]
    need(sorted(sc) == ["late", "serial", "steps"], f"schedules: {sorted(sc)}")
    for k in sc:
        stats(sc[k]["end_to_end_ms"], f"gpu.schedules.{k}.end_to_end_ms", 3 * max(1, reps // 2))
        need(isinstance(sc[k]["barriers"], int) and sc[k]["barriers"] > 0, f"schedules.{k}.barriers")
    need(sc["steps"]["barriers"] < sc["serial"]["barriers"] and sc["late"]["barriers"] < sc["serial"]["barriers"],
         f"schedules: steps {sc['steps']['barriers']} and late {sc['late']['barriers']} barriers against serial "
         f"{sc['serial']['barriers']}")
    need("fps_variants" not in g, "fps_variants: GPUs only (lavapipe's FPS rule was measured)")
    if ilu:
        # The fused node's shaders side by side: the default (wave 1), the shared-memory
        # shader (0), then the register shader at the subgroup size and its doublings to 256.
        v = g["ilu_variants"]
        waves = [row["wave"] for row in v["rows"]]
        need(waves[:2] == [0, 1] and waves[2] >= 1 and all(b == 2 * a for a, b in zip(waves[2:], waves[3:]))
             and waves[-1] <= 256, f"ilu_variants waves {waves}")
        for row in v["rows"]:
            if "refused" in row:
                need(row["wave"] >= 2 and row["refused"], f"ilu_variants refusal {row}")
                continue
            stats(row["ms"], f"ilu_variants wave {row['wave']}", reps)
            # 0: never the register shader; >= 2: always; 1 (the default): on CPU devices only.
            want_wave = row["wave"] >= 2 or (row["wave"] == 1 and r["device"]["type"] == "CPU")
            need((row["shader"] == "ilu_wave") == want_wave and row["shader"] in ("ilu", "ilu_subgroup", "ilu_wave"),
                 f"ilu_variants: wave {row['wave']} ran {row['shader']} on a {r['device']['type']} device")
        st = g["ilu"]["stepped"]
        need(st["n"] == s["stepped"] and len(st["step_ms"]) == st["n"], f"stepped {st}")
        stats(st["per_iteration_ms"], "stepped.per_iteration_ms", s["profile_reps"] * (st["n"] - 1))
    if "cpu" in r:
        backend(r["cpu"], "cpu", s["cpu_reps"], 1, iters, batches, points, ilu)
        need("efficiency" in r["cpu"] and r["cpu"]["efficiency"]["conv"]["fraction_of_peak"] is None,
             "a CPU fraction of the GPU probe")
        for k, v in r["cpu_over_gpu"].items():
            positive(v, f"cpu_over_gpu.{k}")
        need({"end_to_end", "cached_touch", "stage total"} <= set(r["cpu_over_gpu"]), "cpu_over_gpu keys")
    t = r["tracker"]
    for b, runs in (("gpu", reps), ("cpu", s["cpu_reps"])):
        x = t[b]
        need(x["reps"] == runs and x["touches"] > x["window"] == window, f"tracker.{b} runs {x} (window {window} asked)")
        steady = runs * (x["touches"] - x["window"])  # touches past the window, every run
        for k in ("add_touch_ms", "estimate_ms", "touch_ms"):
            stats(x[k], f"tracker.{b}.{k}", steady)
        need(x["hypotheses"] == x["samples"] * x["spins"] and x["hypotheses"] >= 100000, f"tracker.{b} hypotheses")
        positive(x["device_bytes"], f"tracker.{b}.device_bytes")
        positive(x["host_bytes"], f"tracker.{b}.host_bytes")
        need(x["cycle"] == "return", f"tracker.{b}.cycle {x.get('cycle')} (the default: return)")
        positive(x["surface_build_ms"], f"tracker.{b}.surface_build_ms")
    need(t["gpu"]["hypotheses"] == t["cpu"]["hypotheses"], "tracker: both backends run the same hypotheses")
    nodes = t["gpu"]["nodes_ms"]  # one profiled tracker's steady touches, per step node
    need("track.evidence" in nodes, f"tracker.gpu.nodes_ms names the evidence: {sorted(nodes)}")
    for name, st in nodes.items():
        stats(st, f"tracker.gpu.nodes_ms.{name}", t["gpu"]["touches"] - t["gpu"]["window"])
    need(t["cpu"]["nodes_ms"] == {}, "tracker.cpu.nodes_ms: none on the CPU reference")
    positive(t["cpu_over_gpu"], "tracker.cpu_over_gpu")
    gl = r["gel"]  # the gel stage: a frame's shape on both backends, one touch's render-and-compare
    need(gl["size"] == [160, 120], f"gel.size {gl['size']}")
    stats(gl["shape_ms"], "gel.shape_ms", reps)
    stats(gl["shape_cpu_ms"], "gel.shape_cpu_ms", reps)
    # Both solves, 50 sweeps from zeros and the coarse start, on the real frame (whose reader
    # solves from zeros) and on a rendered one (coarse start; docs/gel_shape.md).
    for key, uses in (("solves", "from_zeros"), ("rendered", "coarse_start")):
        need(gl[key]["uses"] == uses, f"gel.{key}.uses {gl[key]['uses']}")
        for solve in ("from_zeros", "coarse_start"):
            s = gl[key][solve]
            stats(s["shape_ms"], f"gel.{key}.{solve}.shape_ms", reps)
            stats(s["solve_gpu_ms"], f"gel.{key}.{solve}.solve_gpu_ms", reps)
            need(s["mask_pixels"] > 0, f"gel.{key}.{solve}: no contact")
        need(gl[key]["from_zeros"]["levels"] == 0 and gl[key]["from_zeros"]["sweeps"] == 50, f"gel.{key}.from_zeros {gl[key]['from_zeros']}")
        need(gl[key]["coarse_start"]["levels"] > 0, f"gel.{key}.coarse_start {gl[key]['coarse_start']}")
    need(gl["rendered"]["coarse_start"]["mask_pixels"] > 10 * gl["solves"]["coarse_start"]["mask_pixels"] // 2,
         "gel.rendered: its contact should be far wider than the real press's")
    cb = gl["codebook"]
    need(cb["hypotheses"] >= 100000 and cb["dense_points"] > 0, f"gel.codebook {cb}")
    positive(cb["render_ms"], "gel.codebook.render_ms")
    stats(cb["score_ms"], "gel.codebook.score_ms", reps)
    with open(plot, "rb") as f:
        head = f.read(24)
    need(head[:8] == b"\x89PNG\r\n\x1a\n", "the plot is not a PNG")
    w, h = int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
    need(w >= 600 and h >= 400, f"plot size {w}x{h}")
    print(f"check_bench_json: {path} ok ({len(g['nodes'])} GPU nodes)")


if __name__ == "__main__":
    a = sys.argv[1:]
    if len(a) != 7:
        fail(__doc__)
    ints = lambda s: [int(x) for x in s.split(",")] if s else []
    try:
        main(a[0], a[1], int(a[2]), ints(a[3]), ints(a[4]), ints(a[5]), int(a[6]))
    except (KeyError, TypeError, IndexError) as e:
        fail(f"the report lacks or mistypes a field: {type(e).__name__} {e}")
