"""The module's results equal the C++ API's (through the CLI, which calls it)
bit for bit, and arrays in give the same results as files in."""

import json
import os
import re
import subprocess

import numpy as np
import pytest
from PIL import Image

import vtloc
from weights_tools import safetensors_io


def run_cli(cli, *args):
    p = subprocess.run([cli, *args], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_localize_equals_the_cli(cli, tiny, tiny_path, mug, touch, root, tmp_path):
    out = json.loads(run_cli(cli, "localize", "--model", tiny_path, "--tactile", touch, "--object",
                             os.path.join(root, "examples", "mug.glb"), "--json", "--dump", str(tmp_path),
                             "--heatmap", str(tmp_path / "cli.ply")))
    r = tiny.localize(mug, touch, keep_tensors=True)
    assert r.contact.tolist() == out["contact"]
    assert r.contact_normalised.tolist() == out["contact_normalised"]
    assert r.iterates.tolist() == out["iterates"]
    assert r.alignment == out["alignment"]
    dumped, _ = safetensors_io.load(str(tmp_path / "tensors.safetensors"))
    assert sorted(r.tensors) == sorted(dumped)
    for name, t in dumped.items():
        assert np.array_equal(r.tensors[name], t.numpy()), name
    assert np.array_equal(r.topk_index, dumped["topk.index"].numpy().reshape(-1))
    assert np.array_equal(r.heatmap, dumped["heatmap"].numpy().reshape(-1))
    vtloc.write_heatmap_ply(str(tmp_path / "py.ply"), mug, r.heatmap)
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()


SEQUENCE_ARGS = ("sequence", "--object", "examples/mug.glb", "--touches", "tests/cli/data/sequence.json",
                 "--geometry-only", "--json")


@pytest.fixture(scope="module")
def mug_sequence(cli, root):
    """`vtloc sequence`'s JSON on the three-touch mug file, geometry alone (run once, read twice)."""
    return json.loads(run_cli(cli, *(os.path.join(root, a) if "/" in a else a for a in SEQUENCE_ARGS)))


def test_tracker_equals_the_cli(mug_sequence, ctx, root):
    seq = os.path.join(root, "tests", "cli", "data", "sequence.json")
    mug_path = os.path.join(root, "examples", "mug.glb")
    out = mug_sequence
    with open(seq) as f:
        spec = json.load(f)
    t = vtloc.Tracker(ctx, mug_path)
    for touch, cli_touch in zip(spec["touches"], out["touches"]):
        m = touch.get("motion")
        if isinstance(m, dict):  # {"Q": 3x3, "q": 3}
            m = np.vstack([np.hstack([np.array(m["Q"]), np.array(m["q"])[:, None]]), [0, 0, 0, 1]])
        t.add_touch(None if m is None else np.array(m, dtype=np.float64))
        e = t.estimate()
        assert e["contact"].tolist() == cli_touch["contact"]
        assert e["pose"].tolist() == cli_touch["pose"]
        assert abs(float(e["sample_belief"].sum()) - 1.0) < 1e-4
    assert t.touches == 3 and t.belief.shape == (t.sample_points.shape[0] * t.n_spin,)
    assert out["hypotheses"] == t.sample_points.shape[0] * t.n_spin
    assert out["memory"] == {"device_bytes": t.device_bytes, "host_bytes": t.host_bytes}  # after the same three touches
    win = t.evaluate_window([np.eye(4)])
    assert len(win["window_poses"]) == 2 and win["pose"].shape == (4, 4)
    # window_fit: the estimate's own pose, refined again, fits at least as well as its `fit`.
    assert t.window_fit([np.eye(4)], win["pose"]) >= win["fit"] - 1e-9
    # A thread budget changes who climbs the modes, not the estimate (with_options: the
    # same surface, not built again).
    one = t.with_options(threads=1).evaluate_window([np.eye(4)])
    assert one["contact"].tolist() == win["contact"].tolist() and one["fit"] == win["fit"]
    with pytest.raises(vtloc.Error, match="threads"):
        vtloc.Tracker(ctx, mug_path, threads=-1)
    bad = np.eye(4)
    bad[0, 0] = 2
    with pytest.raises(vtloc.Error, match="not a rotation"):
        t.window_fit([np.eye(4)], bad)


def test_tracker_profile_times_the_nodes_and_changes_nothing(mug_sequence, cli, ctx, root):
    mug_path = os.path.join(root, "examples", "mug.glb")
    plain = mug_sequence
    timed = json.loads(run_cli(cli, *(os.path.join(root, a) if "/" in a else a for a in SEQUENCE_ARGS), "--profile"))
    for a, b in zip(plain["touches"], timed["touches"]):
        assert "ms" not in a
        assert b["contact"] == a["contact"] and b["pose"] == a["pose"]
        assert b["ms"]["add_touch"] > 0 and b["ms"]["estimate"] >= 0
        names = [n["node"] for n in b["ms"]["nodes"]]
        assert names.count("track.evidence") == 1 and all(n["ms"] >= 0 for n in b["ms"]["nodes"])
    t = vtloc.Tracker(ctx, mug_path, hypotheses=5000, profile=True)
    u = t.with_options(profile=False)
    assert t.options["profile"] and not u.options["profile"] and t.step_nodes == []
    for tr in (t, u):
        tr.add_touch(None)
    nodes = t.step_nodes
    assert [name for name, _ in nodes].count("track.evidence") == 1 and all(ms >= 0 for _, ms in nodes)
    assert u.step_nodes == []
    assert np.array_equal(t.estimate()["sample_belief"], u.estimate()["sample_belief"])


def test_tracker_with_options_equals_one_made_so(ctx, root):
    mug_path = os.path.join(root, "examples", "mug.glb")
    t = vtloc.Tracker(ctx, mug_path, hypotheses=5000)
    u = t.with_options(odometry_mm=0.5, window=2, sigma_d_mm=1.3)
    made = vtloc.Tracker(ctx, mug_path, hypotheses=5000, odometry_mm=0.5, window=2, sigma_d_mm=1.3)
    step = np.eye(4)
    step[:3, 3] = [5.0, 0.0, 0.0]
    for tr in (u, made):
        tr.add_touch(None)
        tr.add_touch(step)
        tr.add_touch(step)
    a, b = u.estimate(), made.estimate()
    assert a["contact"].tolist() == b["contact"].tolist()
    assert a["pose"].tolist() == b["pose"].tolist()
    assert np.array_equal(a["sample_belief"], b["sample_belief"])
    assert t.touches == 0 and u.touches == 3
    with pytest.raises(vtloc.Error, match="n_spin"):
        t.with_options(n_spin=18)
    with pytest.raises(vtloc.Error, match="bogus"):
        t.with_options(bogus=1)
    with pytest.raises(vtloc.Error, match="window"):
        t.with_options(window=0)
    with pytest.raises(vtloc.Error, match="odometry_mm has the wrong type"):
        t.with_options(odometry_mm="far")
    # options names every knob with_options takes: each goes back in as it came out.
    opts = t.options
    assert opts["hypotheses"] == 5000 and opts["candidates"] is None and u.options["window"] == 2
    for k, v in opts.items():
        if k != "candidates":
            assert t.with_options(**{k: v}).options == opts, k
    # The search's knobs, which only with_options sets, reach the engine.
    quick = t.with_options(deep_modes=0, register_rounds=0, rescue_modes=4, refine_reach_mm=0)
    assert (quick.options["deep_modes"], quick.options["register_rounds"], quick.options["rescue_modes"]) == (0, 0, 4)
    for bad, name in (({"deep_modes": 65}, "deep_modes"), ({"register_rounds": -1}, "register_rounds"),
                      ({"rescue_fit": float("nan")}, "rescue_fit"), ({"mode_radius_mm": 0.0}, "mode_radius_mm")):
        with pytest.raises(vtloc.Error, match=name):
            t.with_options(**bad)


def test_batch_equals_single_touches(tiny, mug, root):
    frames = [vtloc.load_tactile_image(os.path.join(root, "examples", f"touch_0{i}.png")) for i in (1, 2, 3)]
    batch = tiny.localize(mug, frames)
    assert isinstance(batch, list) and len(batch) == 3
    for im, b in zip(frames, batch):
        one = tiny.localize(mug, im)
        for field in ("contact", "iterates", "topk_index", "topk_score", "heatmap"):
            assert np.array_equal(getattr(one, field), getattr(b, field)), field


def test_arrays_in_equal_files_in(tiny, mug, touch):
    again = tiny.encode_object(mug.cloud, mug.candidates)
    image = vtloc.load_tactile_image(touch)
    assert image.dtype == np.uint8 and image.shape[2] == 3
    a, b = tiny.localize(mug, touch), tiny.localize(again, image)
    assert np.array_equal(a.contact, b.contact) and np.array_equal(a.heatmap, b.heatmap)
    # float64 points are the same points
    c = tiny.localize(tiny.encode_object(mug.cloud.astype(np.float64)), image)
    assert np.array_equal(a.contact, c.contact)


def test_result_arrays(tiny, mug, touch):
    r = tiny.localize(mug, touch, top_k=7, iters=3)
    info = tiny.info
    assert r.iterates.shape == (3, 3) and r.contact.shape == (3,)
    assert r.topk_index.dtype == np.int32 and r.topk_index.shape == (7,)
    assert r.topk_point.shape == (7, 3) and r.topk_score.dtype == np.float32
    assert np.array_equal(r.topk_point, mug.candidates[r.topk_index].astype(np.float64))
    assert r.heatmap.shape == (mug.cloud.shape[0],) and 0 <= r.heatmap.min() and r.heatmap.max() <= 1
    assert info["name"] == "vtloc-tiny" and info["head"] == "ilu"
    assert r.timings["wall_ms"] > 0
    assert tiny.localize(mug, touch, gma=False).alignment is None


def test_cpu_backend_matches_gpu(tiny_path, tiny, mug, touch):
    cpu_only = vtloc.Model(tiny_path)
    obj = cpu_only.encode_object(mug.cloud, backend="cpu")
    a = cpu_only.localize(obj, touch, backend="cpu")
    b = tiny.localize(mug, touch)
    # end-to-end fp32 through two implementations: the tolerance `vtloc check` uses end to end
    assert np.all(np.abs(a.contact - b.contact) <= 2e-3 + 2e-3 * np.abs(b.contact))
    try:
        cpu_only.localize(obj, touch)
        raise AssertionError("a CPU-only model ran on the GPU")
    except vtloc.Error as e:
        assert "without a GPU context" in str(e)


def test_outputs_and_info(tiny, mug, touch, tiny_path, tmp_path):
    r = tiny.localize(mug, touch)
    vtloc.render_heatmap_png(str(tmp_path / "h.png"), mug, r.heatmap, contact=r.contact, caption="py",
                             tactile=touch)
    assert (tmp_path / "h.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    info = vtloc.inspect_model(tiny_path)
    assert info["parameter_count"] > 0 and len(info["tensors"]) > 0
    assert any(d["name"] for d in vtloc.list_devices())
    # CPU devices name the host's vector registers (16 or 32), GPUs 0.
    assert all(d["host_vector_registers"] == 0 if d["type"] != "CPU" else d["host_vector_registers"] in (16, 32)
               for d in vtloc.list_devices())
    # A device's profile (vtloc-bench --plan-for) says what list_devices says.
    d0 = vtloc.list_devices()[0]
    prof = json.loads(vtloc.device_profile(d0["index"]))
    assert prof["format"] == "vtloc-device-profile/1" and prof["name"] == d0["name"]
    assert prof["subgroup_size"] == d0["subgroup_size"] and prof["compute_units"] == d0["compute_units"]
    with pytest.raises(vtloc.Error, match="no Vulkan device with index 99"):
        vtloc.device_profile(99)


def test_cloud_without_normals_equals_the_cli(cli, tiny, tiny_path, mug, touch, tmp_path):
    """An N x 3 array and the same points as an .xyz file: normals estimated the same
    way (on the GPU), the same result through the module and the CLI."""
    xyz = np.ascontiguousarray(mug.cloud[:, :3])
    np.savetxt(tmp_path / "mug.xyz", xyz, fmt="%.9g")  # 9 digits: float32 round-trips
    obj = tiny.encode_object(xyz)
    assert obj.normals_estimated and not mug.normals_estimated
    assert np.array_equal(obj.cloud[:, :3], xyz)
    assert np.allclose(np.linalg.norm(obj.cloud[:, 3:], axis=1), 1, atol=1e-5)
    out = json.loads(run_cli(cli, "localize", "--model", tiny_path, "--tactile", touch, "--object",
                             str(tmp_path / "mug.xyz"), "--json"))
    assert out["object"]["normals"].startswith("estimated")
    assert tiny.localize(obj, touch).contact.tolist() == out["contact"]


def _sphere_depth(path):
    """A 160 x 120 16-bit depth PNG of a 40 mm sphere 400 mm ahead (fx 300, fy 310)."""
    from PIL import Image
    v, u = np.mgrid[0:120, 0:160]
    rx, ry = (u - 79.5) / 300.0, (v - 59.5) / 310.0
    a, b, c = rx * rx + ry * ry + 1, -800.0, 400.0 ** 2 - 40.0 ** 2
    disc = b * b - 4 * a * c
    z = np.where(disc >= 0, (-b - np.sqrt(np.maximum(disc, 0))) / (2 * a), 0)
    Image.fromarray(np.round(z).astype(np.uint16)).save(path)
    return (300.0, 310.0, 79.5, 59.5)


def test_depth_view_equals_the_cli(cli, tiny, tiny_path, touch, tmp_path):
    k = _sphere_depth(tmp_path / "depth.png")
    obj = tiny.encode_depth(str(tmp_path / "depth.png"), k)
    assert obj.normals_estimated and obj.source_points == obj.cloud.shape[0]
    # facing the camera at the origin
    assert np.all((obj.cloud[:, :3] * obj.cloud[:, 3:]).sum(1) < 0)
    # an array with the camera as viewpoint: the same object
    again = tiny.encode_object(np.ascontiguousarray(obj.cloud[:, :3]), viewpoint=(0, 0, 0))
    assert np.array_equal(again.cloud, obj.cloud)
    out = json.loads(run_cli(cli, "localize", "--model", tiny_path, "--tactile", touch, "--depth",
                             str(tmp_path / "depth.png"), "--intrinsics", ",".join(map(str, k)), "--json"))
    assert tiny.localize(obj, touch).contact.tolist() == out["contact"]
    with pytest.raises(vtloc.Error, match="intrinsics: expected 4 numbers"):
        tiny.encode_depth(str(tmp_path / "depth.png"), (1, 2, 3))
    with pytest.raises(vtloc.Error, match="viewpoint: only for clouds given as arrays"):
        tiny.encode_object(str(tmp_path / "depth.png"), viewpoint=(0, 0, 0))


def test_tracker_candidates_protocol(ctx, root):
    mug_path = os.path.join(root, "examples", "mug.glb")
    cands = np.loadtxt(os.path.join(root, "examples", "mug_candidates.csv"), delimiter=",", comments="#")
    t = vtloc.Tracker(ctx, mug_path, candidates=cands)
    # One hypothesis sample per candidate, at the candidate itself.
    assert t.sample_points.shape == (len(cands), 3)
    assert np.allclose(t.sample_points, cands, atol=1e-4)
    t.add_touch()
    assert t.estimate()["sample_belief"].shape == (len(cands),)
    with pytest.raises(vtloc.Error, match="C x 3"):
        vtloc.Tracker(ctx, mug_path, candidates=np.zeros((4, 2)))


def test_checks_match_the_cli(cli, ctx, root, tiny_path, touch, tmp_path):
    mug_path = os.path.join(root, "examples", "mug.glb")
    r = vtloc.check(ctx, tiny_path, touch, mug_path)
    assert r["ok"] and r["first_failure"] is None and r["device"] == ctx.device["name"]
    run_cli(cli, "check", "--model", tiny_path, "--tactile", touch, "--object", mug_path, "--json", str(tmp_path / "m.json"))
    with open(tmp_path / "m.json") as f:
        m = json.load(f)
    assert [n["node"] for n in r["nodes"]] == [n["node"] for n in m["nodes"]]
    assert [o["name"] for o in r["outputs"]] == [o["name"] for o in m["outputs"]]
    tour = os.path.join(root, "examples", "potato_tour.json")
    t = vtloc.check_tracker(ctx, tour, hypotheses=12000)
    assert t["ok"] and len(t["touches"]) == 15 and all(x["ok"] for x in t["touches"])
    assert [n["op"] for n in t["nodes"]] == ["pose_evidence", "log_softmax", "spin_marginal", "expected_distance"]
    assert t["tolerance"]["belief"] == {"abs": 1e-6, "rel": 5e-3}
    one_way = vtloc.check_tracker(ctx, tour, hypotheses=12000, there_and_back=False, touch_terms=True)
    assert one_way["ok"] and len(one_way["touches"]) == 8 and one_way["hypotheses"] == t["hypotheses"]
    # The frames' shapes (the rendered frames' reader: its coarse start's nodes too) and 16 of the
    # codebook's maps, checked exactly against the CPU's render (all of them by default: C++'s test).
    shapes = vtloc.check_tracker(ctx, tour, hypotheses=6000, there_and_back=False, shapes=True, codebook_samples=16,
                                 rendered_frames=True)
    assert shapes["ok"] and [os.path.basename(s["frame"]) for s in shapes["shape_terms"]] == \
        [f"potato_tour_{i}.png" for i in range(1, 9)]
    assert all(s["ok"] for s in shapes["shape_terms"]) and shapes["tolerance"]["term"] == {"abs": 1e-4, "rel": 1e-4}
    book = shapes["codebook"]
    assert book["ok"] and book["checked"] == 16 and book["samples"] * 36 == shapes["hypotheses"] and book["cache"] == ""
    assert book["heights"]["max_abs"] == 0 and shapes["tolerance"]["height"] == {"abs": 0, "rel": 0}
    assert "codebook" not in one_way and shapes["first_shape_failure"] is None and one_way["first_shape_failure"] is None
    for s in shapes["shape_terms"]:  # the reader's graph on each frame, node by node, and the shape it read
        ops = [n["op"] for n in s["shape"]["nodes"]]
        assert len(ops) == 11 and ops[:2] == ["gel_gradient", "gel_contact_mask"] and ops[-1] == "masked_poisson"
        assert all(n["ok"] for n in s["shape"]["nodes"]) and len(s["shape"]["outputs"]) == 3
        assert s["shape"]["first_failure"] is None
        assert s["shape"]["depth"]["max_abs"] == 0 and s["shape"]["mask_pixels_differ"] == 0
    with pytest.raises(vtloc.Error, match="no_such_tour.json"):
        vtloc.check_tracker(ctx, os.path.join(root, "examples", "no_such_tour.json"))


def test_gel_shape_reader(ctx, root, tmp_path):
    reader = vtloc.GelShapeReader(ctx)
    frame = os.path.join(root, "examples", "touch_01.png")  # a real 4 mm ball press
    s = reader.read(frame)
    assert s["depth_mm"].shape == (reader.height, reader.width) and s["mask"].dtype == np.uint8
    assert s["mask"].sum() > 100 and 0.2 < float(s["depth_mm"].max()) < 4.0
    assert np.all(s["depth_mm"][s["mask"] == 0] == 0)
    none = reader.read(frame, empty=frame)  # the frame as its own background: nothing pressed
    assert none["mask"].sum() == 0
    with pytest.raises(vtloc.Error, match="^frame: 100x100 .*another aspect"):
        reader.read(np.zeros((100, 100, 3), np.uint8))
    # A frame given by its path is named in the error (a square crop of the press: another aspect).
    crop = os.path.join(str(tmp_path), "square.png")
    with Image.open(frame) as im:
        im.crop((0, 0, im.size[1], im.size[1])).save(crop)
    with pytest.raises(vtloc.Error, match="^" + re.escape(crop) + ": .*another aspect"):
        reader.read(crop)
    with pytest.raises(vtloc.Error, match="^" + re.escape(crop) + ": .*another aspect"):
        reader.read(frame, empty=crop)
    # check_frame: the same refusals without reading; nothing for a frame read() takes.
    assert reader.check_frame(frame) is None and reader.check_frame(frame, empty=frame) is None
    with pytest.raises(vtloc.Error, match="^" + re.escape(crop) + ": .*another aspect"):
        reader.check_frame(frame, empty=crop)
    with pytest.raises(vtloc.Error, match="^frame: the frame is black"):
        reader.check_frame(np.zeros((120, 160, 3), np.uint8))
    # The solve from a coarse start (the rendered frames' reader): the same contact, the same
    # depth within 3 % of the deepest point (measured 1.5 %: 54 um of 3.6 mm; the 50 sweeps from
    # zeros are within 3 um of 1000 on this small contact, where the coarse grids see little).
    coarse = vtloc.GelShapeReader(ctx, levels=2, coarse_iterations=30, iterations=10, threads=1).read(frame)
    assert np.array_equal(coarse["mask"], s["mask"])
    assert float(np.abs(coarse["depth_mm"] - s["depth_mm"]).max()) < 0.03 * float(s["depth_mm"].max())
    with pytest.raises(vtloc.Error, match="levels must be 0..8"):
        vtloc.GelShapeReader(ctx, levels=9)
    with pytest.raises(vtloc.Error, match="threads must be 0..256"):
        vtloc.GelShapeReader(ctx, threads=-1)


def test_tracker_render_and_compare(ctx, root, tmp_path):
    # A 0.8 mm cap pressed into the gel (as GelShapeReader.read gives it), scored against every pose on the potato.
    obj = os.path.join(root, "examples", "potato_tour.ply")
    cache = str(tmp_path / "potato.codebook")
    t = vtloc.Tracker(ctx, obj, hypotheses=20000, codebook_cache=cache)
    r, c = np.mgrid[0:120, 0:160] * 0.1245
    cap = np.maximum(0.0, 0.8 - ((r - 7.5) ** 2 + (c - 10.0) ** 2) / 40.0).astype(np.float32)
    shape = {"depth_mm": cap, "mm_per_px": 0.1245}
    before = t.device_bytes
    # Host memory: at least the hypotheses' samples (9 floats) and their points in the tables (3).
    assert t.host_bytes >= len(t.sample_points) * 12 * 4
    term = t.shape_term(shape)
    assert t.device_bytes >= before + len(t.sample_points) * 27 * 27 * 4  # the codebook's maps are counted
    assert term.shape == (len(t.sample_points) * t.n_spin,) and np.all(term <= 0) and term.min() < term.max()
    assert os.path.exists(cache)
    t.add_touch(shape=shape)
    e = t.estimate()
    assert e["touches"] == 1 and abs(float(t.belief.sum()) - 1) < 1e-3
    t.reset()  # forgets the touch, keeps the object
    assert t.touches == 0
    with pytest.raises(vtloc.Error, match="no touch"):
        t.estimate()
    t.add_touch(shape=shape)
    assert np.array_equal(t.estimate()["contact"], e["contact"])
    belief = t.belief
    t.reset()
    t.add_touch_term(term=term, shape=shape)  # the same touch through its precomputed term (and its shape)
    assert np.array_equal(t.belief, belief)
    assert np.array_equal(t.estimate()["contact"], e["contact"])
    with pytest.raises(vtloc.Error, match="7 values"):
        t.add_touch_term(np.eye(4), np.zeros(7, np.float32))
    # A second tracker reads the cache and scores the same.
    t2 = vtloc.Tracker(ctx, obj, hypotheses=20000, codebook_cache=cache)
    assert np.array_equal(t2.shape_term(shape), term)
    # The score's knobs: the plane alone and the deepest cell as the press score otherwise; a bad percentile is named.
    t3 = vtloc.Tracker(ctx, obj, hypotheses=20000, codebook_cache=cache, render_quadratic=False, render_press_percentile=100.0)
    assert not np.array_equal(t3.shape_term(shape), term)
    with pytest.raises(vtloc.Error, match="render_press_percentile"):
        vtloc.Tracker(ctx, obj, hypotheses=20000, render_press_percentile=0.0)
    t4 = vtloc.Tracker(ctx, obj, hypotheses=20000, codebook_cache=cache, render_cell_mm=1.0)
    assert not np.array_equal(t4.shape_term(shape), term)
    with pytest.raises(vtloc.Error, match="render_cell_mm"):
        vtloc.Tracker(ctx, obj, hypotheses=20000, render_cell_mm=0.0)
    # The windowed form over precomputed terms: the same as the geometry alone when none, and the term
    # counts when given.
    step = np.eye(4)
    step[0, 3] = 3.0
    # The shapes also score the refined poses (render_refined_weight; at 0 they only enter through the terms).
    t0 = t.with_options(render_refined_weight=0.0)
    assert np.array_equal(t0.evaluate_window([step], terms=[term, term], shapes=[shape, shape])["sample_belief"],
                          t0.evaluate_window([step], terms=[term, term])["sample_belief"])
    # With odometry noise the earlier shape is scored where it matches within the noise (render_slack_rounds).
    noisy = t.with_options(odometry_mm=0.5)
    assert not np.array_equal(noisy.evaluate_window([step], terms=[term, term], shapes=[shape, shape])["sample_belief"],
                              noisy.with_options(render_slack_rounds=0).evaluate_window(
                                  [step], terms=[term, term], shapes=[shape, shape])["sample_belief"])
    # And the grid reads the earlier term widened within the noise (field_slack), in the constructor too
    # (sharpened, at 2 mm: the term's ~0.04 nats are far less than a neighbour ~4 mm away costs at 0.5 mm).
    sharp, wide = term * 1000, t.with_options(odometry_mm=2.0, field_slack=True)
    assert not np.array_equal(wide.evaluate_window([step], terms=[sharp, sharp])["sample_belief"],
                              wide.with_options(field_slack=False).evaluate_window([step], terms=[sharp, sharp])["sample_belief"])
    assert np.array_equal(wide.evaluate_window([step], terms=[sharp, sharp])["sample_belief"],
                          vtloc.Tracker(ctx, obj, hypotheses=20000, odometry_mm=2.0, field_slack=True).evaluate_window(
                              [step], terms=[sharp, sharp])["sample_belief"])
    with pytest.raises(vtloc.Error, match="render_slack_rounds must be 0..8"):
        t.with_options(render_slack_rounds=9)
    with pytest.raises(vtloc.Error, match="render_slack_rounds must be 0..8"):
        vtloc.Tracker(ctx, obj, hypotheses=20000, render_slack_rounds=-1)
    # One touch's floor at the refined poses (render_refined_floor): without one the window scores otherwise.
    bare = t.with_options(render_refined_floor=float("-inf"))
    assert (bare.evaluate_window([step], shapes=[shape, shape])["pose_terms"]
            != t.evaluate_window([step], shapes=[shape, shape])["pose_terms"])
    with pytest.raises(vtloc.Error, match="render_refined_floor"):
        t.with_options(render_refined_floor=float("nan"))
    with pytest.raises(vtloc.Error, match="1 gel shapes for 2 touches"):
        t.evaluate_window([step], terms=[term, term], shapes=[shape])
    geo = t.evaluate_window([step])
    assert geo["pose_terms"] == 0  # no shapes: no score at the refined poses
    assert t.evaluate_window([step], terms=[term, term], shapes=[shape, shape])["pose_terms"] < 0
    assert np.array_equal(t.evaluate_window([step], terms=[None, None])["sample_belief"], geo["sample_belief"])
    both = t.evaluate_window([step], terms=[term, term])
    assert not np.array_equal(both["sample_belief"], geo["sample_belief"])
    with pytest.raises(vtloc.Error, match="1 touch terms for 2 touches"):
        t.evaluate_window([step], terms=[term])
    with pytest.raises(vtloc.Error, match="depth_mm and mm_per_px"):
        t.add_touch(np.eye(4), shape={"depth_mm": shape["depth_mm"]})
