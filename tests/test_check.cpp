// `vtloc check` through the public API: the model check passes on lavapipe
// for the tiny model, fails naming the node when a test-only fault injector
// corrupts one node's GPU output (fp32 and index outputs), and the op
// self-test covers every registered op and passes. Validation layer on.
#include <catch2/catch.hpp>
#include <filesystem>
#include <set>

#include "engine/check/fault_injection.h"
#include "engine/executor.h"
#include "engine/op.h"
#include "engine/ops/build.h"
#include "engine/safetensors.h"
#include "tests/api_test_util.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

api::CheckOptions tiny_check() {
    return {test::tiny_model(), test::source_path("examples/touch_01.png"), test::source_path("examples/mug.glb")};
}

// Clears the fault even when a REQUIRE fails.
struct FaultGuard {
    ~FaultGuard() { check::testing::clear_fault(); }
};

}  // namespace

TEST_CASE("check: the tiny model passes on this device, every node compared", "[check]") {
    api::Context ctx(test::validated());
    api::CheckResult r = api::check(ctx, tiny_check());
    test::require_no_validation(ctx);
    INFO("first failure " << (r.first_failure >= 0 ? r.nodes[size_t(r.first_failure)].node : "none"));
    CHECK(r.ok);
    CHECK(r.first_failure == -1);
    CHECK(r.nodes.size() > 20);
    std::set<std::string> ops, outputs;
    for (const api::NodeCheck& n : r.nodes) {
        ops.insert(n.op);
        CHECK(n.ok);
        CHECK(n.error.tolerance_used <= 1.0);
        // Shader and spec constants reported; flatten and a one-row concat are buffer copies.
        if (n.op != "flatten" && n.op != "concat") CHECK(!n.dispatches.empty());
    }
    // The tiny model's ILU ends in its retrieval's dispatch (engine/ops/ilu_retrieve.cpp).
    for (const char* op : {"tactile_preprocess", "conv2d", "fps", "ball_query", "ilu_retrieve"}) CHECK(ops.count(op));
    for (const api::OutputCheck& o : r.outputs) outputs.insert(o.name);
    for (const char* name : {"contact", "topk.index", "heatmap", "point.sa1.fps"}) CHECK(outputs.count(name));
    for (const api::NodeCheck& n : r.nodes)
        if (n.op == "fps" || n.op == "ilu_retrieve") CHECK((n.error.has_indices && n.error.indices_equal));
    CHECK(r.node_tolerance.abs == 1e-4);
    CHECK(r.end_to_end_tolerance.rel == 2e-3);
    CHECK(!r.device.driver.empty());
}

TEST_CASE("check: a corrupted GPU output fails the check and names its node", "[check]") {
    api::Context ctx(test::validated());
    api::CheckResult clean = api::check(ctx, tiny_check());
    for (const api::NodeCheck& n : clean.nodes)
        if (!n.ok) FAIL_CHECK("node " << n.node << " (" << n.op << "): " << n.error.first_mismatch << n.failure);
    for (const api::OutputCheck& o : clean.outputs)
        if (!o.ok) FAIL_CHECK("output " << o.name << ": " << o.error.first_mismatch);
    REQUIRE(clean.ok);
    FaultGuard guard;
    for (const char* op : {"conv2d", "fps"}) {
        std::string node;
        for (const api::NodeCheck& n : clean.nodes)
            if (n.op == op && node.empty()) node = n.node;
        REQUIRE(!node.empty());
        INFO("corrupting " << node << " (" << op << ")");
        check::testing::set_fault(node, [](HostTensor& t) {
            // fp32: one element off by 1e-2; indices: one index shifted by one.
            if (t.type == ElemType::I32) t.set_int(t.data.size() / 2, t.int_at(t.data.size() / 2) + 1);
            else t.data[t.data.size() / 2] += 1e-2f;
        });
        api::CheckResult r = api::check(ctx, tiny_check());
        check::testing::clear_fault();
        CHECK(!r.ok);
        REQUIRE(r.first_failure >= 0);
        const api::NodeCheck& bad = r.nodes[size_t(r.first_failure)];
        CHECK(bad.node == node);
        CHECK(bad.op == op);
        CHECK(!bad.ok);
        CHECK(bad.error.mismatches >= 1);
        CHECK(bad.error.first_mismatch.find("element") != std::string::npos);
        if (std::string(op) == "fps") CHECK(!bad.error.indices_equal);
        else CHECK(bad.error.max_abs == Approx(1e-2).epsilon(1e-2));
    }
    test::require_no_validation(ctx);
    // Cleared: the next check passes again.
    CHECK(api::check(ctx, tiny_check()).ok);
}

TEST_CASE("check: the tracker check walks the tour there and back and names a corrupted node", "[check][tracker]") {
    api::Context ctx(test::validated());
    api::TrackerCheckOptions o;
    o.touches = test::source_path("examples/potato_tour.json");
    o.hypotheses = 12000;
    const api::TrackerCheckResult r = api::check_tracker(ctx, o);
    for (const api::TouchCheck& t : r.touches)
        if (!t.ok) FAIL_CHECK("touch " << t.touch << ": " << t.belief.first_mismatch);
    for (const api::NodeCheck& n : r.nodes)
        if (!n.ok) FAIL_CHECK("node " << n.node << " (" << n.op << "): " << n.error.first_mismatch << n.failure);
    REQUIRE(r.ok);
    CHECK(r.touches.size() == 15);  // 8 touches, then back over 7 motions
    CHECK(r.object.find("potato_tour.ply") != std::string::npos);
    CHECK(r.hypotheses > 0);
    std::set<std::string> ops;
    for (const api::NodeCheck& n : r.nodes) ops.insert(n.op);
    CHECK(ops == std::set<std::string>{"pose_evidence", "log_softmax", "spin_marginal", "expected_distance"});
    // The last step is the steady state: the window's 7 motions and the prior as terms, the
    // prior's field read.
    const api::NodeCheck& ev = r.nodes.front();
    REQUIRE(ev.op == "pose_evidence");
    REQUIRE(ev.input_shapes.size() == 6);
    CHECK(ev.input_shapes[4] == std::vector<int64_t>{8, 16});
    CHECK(ev.input_shapes[5][0] == 1);
    CHECK(r.outputs.size() == 4);
    {  // With a term each touch the step reads a field per touch of the window, then the prior's.
        api::TrackerCheckOptions t = o;
        t.touch_terms = true;
        t.hypotheses = 6000;
        const api::TrackerCheckResult rt = api::check_tracker(ctx, t);
        CHECK(rt.ok);
        REQUIRE(!rt.nodes.empty());
        REQUIRE(rt.nodes.front().input_shapes.size() == 6);
        CHECK(rt.nodes.front().input_shapes[5] == std::vector<int64_t>{9, rt.hypotheses});
        // Instead, each frame's render-and-compare term: the device's against the CPU reference
        // scorer's, one per frame of the file, then the device's given to both trackers.
        // The codebook goes to a cache (written, as a tracker would, from the device's render).
        const std::string cache = test::temp_path("check_tracker_book.safetensors");
        std::filesystem::remove(cache);
        t.touch_terms = false, t.shapes = true, t.codebook_cache = cache;
        const api::TrackerCheckResult rs = api::check_tracker(ctx, t);
        CHECK(rs.ok);
        CHECK(rs.first_shape_failure == -1);
        REQUIRE(rs.shape_terms.size() == 8);
        for (const api::ShapeTermCheck& c : rs.shape_terms) {
            INFO(c.frame);
            CHECK(c.ok);
            CHECK(c.frame.find("potato_tour_") != std::string::npos);
            // The real frames' reader: gradients, the mask, 50 sweeps from zeros.
            std::vector<std::string> ops;
            for (const api::NodeCheck& n : c.shape_nodes) ops.push_back(n.op);
            CHECK(ops == std::vector<std::string>{"gel_gradient", "gel_contact_mask", "masked_poisson"});
            CHECK(c.shape_outputs.size() == 3);
            // The shape the term scored (the reader's own executor) is the CPU reference run's.
            CHECK(c.depth.max_abs == 0);
            CHECK(c.mask_pixels_differ == 0);
        }
        CHECK(rs.touches.size() == 15);
        CHECK(rs.nodes.front().input_shapes[5] == std::vector<int64_t>{9, rs.hypotheses});
        // The maps scored against, all of them, match the CPU reference's render exactly.
        CHECK(rs.codebook.ok);
        CHECK(rs.codebook.checked == rs.codebook.samples);
        CHECK(rs.codebook.samples * 36 == rs.hypotheses);
        CHECK(rs.codebook.heights.max_abs == 0);
        // A deployed cache one cell off (well formed, so a tracker would score against it): the
        // check names it; the terms, both scored over it, still agree. One way from here: these
        // runs are about the frames and the codebook, not the tour.
        REQUIRE(std::filesystem::exists(cache));
        t.there_and_back = false;
        {
            const SafetensorsFile f = SafetensorsFile::load(cache, "test");
            std::vector<float> h = f.to_f32(f.at("heights"));
            const size_t GG = h.size() / size_t(rs.codebook.samples);
            h[5] -= 0.5f;       // sample 0's, which every spread checks
            h[GG + 5] -= 0.5f;  // sample 1's, which 64 spread over more than 128 do not (the next is sample S / 64)
            write_safetensors(cache, {TensorBlob::f32("heights", f.at("heights").shape, h),
                                      TensorBlob::f32("samples", f.at("samples").shape, f.to_f32(f.at("samples")))},
                              f.metadata());
        }
        REQUIRE(rs.codebook.samples > 128);
        t.codebook_samples = 64;
        const api::TrackerCheckResult stale = api::check_tracker(ctx, t);
        CHECK(!stale.ok);
        CHECK(!stale.codebook.ok);
        CHECK(stale.codebook.heights.mismatches == 1);
        REQUIRE(stale.shape_terms.size() == 8);
        for (const api::ShapeTermCheck& c : stale.shape_terms) CHECK(c.ok);
        CHECK(std::filesystem::exists(cache));  // a cache the check did not write stays
        t.codebook_samples = 0;
        CHECK(api::check_tracker(ctx, t).codebook.heights.mismatches == 2);
        t.codebook_samples = -1;
        CHECK_THROWS_WITH(api::check_tracker(ctx, t), Catch::Contains("codebook_samples"));
        std::filesystem::remove(cache);
        t.codebook_samples = 0;
        {  // The shape's solve off by half a pixel in one pixel: each frame names that node, the
           // terms (scored on the reader's own shapes) still agree. And the device's render of the
           // codebook one cell off: the cache this check wrote from it is removed again.
            FaultGuard g;
            check::testing::set_fault("gel.height", [](HostTensor& z) { z.data[z.data.size() / 2] += 0.5f; });
            check::testing::set_fault("codebook.heights", [](HostTensor& h) { h.data[7] += 0.25f; });
            t.rendered_frames = true;  // and the rendered frames' reader: its coarse start's nodes too
            const api::TrackerCheckResult bad_shape = api::check_tracker(ctx, t);
            t.rendered_frames = false;
            CHECK(!bad_shape.ok);
            CHECK(!bad_shape.codebook.ok);
            CHECK(bad_shape.codebook.heights.mismatches == 1);
            CHECK(!std::filesystem::exists(cache));
            REQUIRE(bad_shape.shape_terms.size() == 8);
            CHECK(bad_shape.first_shape_failure == 0);
            CHECK(bad_shape.first_failure == -1);  // the step itself is sound
            for (const api::ShapeTermCheck& c : bad_shape.shape_terms) {
                CHECK(!c.ok);
                CHECK(c.term.mismatches == 0);
                REQUIRE(c.shape_nodes.size() == 11);
                for (const api::NodeCheck& n : c.shape_nodes) CHECK(n.ok == (n.node != "gel.height"));
                REQUIRE(c.first_failure >= 0);
                CHECK(c.shape_nodes[size_t(c.first_failure)].node == "gel.height");
                CHECK(c.depth.mismatches == 0);  // the fault is the checked copy's: the reader's own shape is sound
            }
        }
        t.codebook_cache.clear();
        t.touch_terms = true;
        CHECK_THROWS_WITH(api::check_tracker(ctx, t), Catch::Contains("not both"));
        // The shapes' options without shapes: refused, not ignored.
        t.touch_terms = false, t.shapes = false, t.background = "bg.png";
        CHECK_THROWS_WITH(api::check_tracker(ctx, t), Catch::Contains("are for shapes"));
    }
    // One probability off: the belief's node (and only the step's node check: the tours ran clean) fails.
    FaultGuard guard;
    check::testing::set_fault("track.belief", [](HostTensor& t) { t.data[t.data.size() / 2] += 1e-2f; });
    const api::TrackerCheckResult bad = api::check_tracker(ctx, o);
    check::testing::clear_fault();
    CHECK(!bad.ok);
    REQUIRE(bad.first_failure >= 0);
    CHECK(bad.nodes[size_t(bad.first_failure)].node == "track.belief");
    for (const api::TouchCheck& t : bad.touches) CHECK(t.ok);
    // Bad input: one line naming the file.
    api::TrackerCheckOptions missing = o;
    missing.touches = test::source_path("examples/no_such_tour.json");
    CHECK_THROWS_WITH(api::check_tracker(ctx, missing), Catch::Contains("no_such_tour.json"));
    api::TrackerCheckOptions none;
    CHECK_THROWS_WITH(api::check_tracker(ctx, none), Catch::Contains("a touches file is needed"));
    test::require_no_validation(ctx);
}

TEST_CASE("check: a bad weight file is one api::Error line", "[check]") {
    api::Context ctx(test::validated());
    api::CheckOptions o = tiny_check();
    o.model = test::source_path("examples/mug.glb");
    std::string m = test::api_error([&] { api::check(ctx, o); });
    CHECK(m.find("mug.glb") != std::string::npos);
}

// Not [op]: each op's own tests run at subgroup 4 in the README's command; this,
// at 4 (~40 s cold: ~160 pipelines), in the long suite ([selftest]).
TEST_CASE("check: the op self-test covers every registered op and passes", "[check][selftest]") {
    api::Context ctx(test::validated());
    size_t seen = 0;
    api::OpsCheckResult r = api::check_ops(ctx, "", [&](size_t i, size_t n, const api::OpCheck& c) {
        CHECK(i == seen++);
        CHECK(i < n);
        INFO(c.op << ": " << c.variant << " " << c.failure << " " << c.error.first_mismatch);
        CHECK(c.ok);
    });
    test::require_no_validation(ctx);
    CHECK(r.ok);
    CHECK(r.uncovered_ops.empty());
    CHECK(seen == r.cases.size());
    std::set<std::string> covered;
    for (const api::OpCheck& c : r.cases) covered.insert(c.op);
    for (std::string_view op : op_names()) CHECK(covered.count(std::string(op)));
    // Both binding paths of the ops that have them.
    for (const char* op : {"conv2d", "max_pool2d", "group_linear"}) {
        bool texel = false, storage = false;
        for (const api::OpCheck& c : r.cases)
            if (c.op == op) {
                texel = texel || c.variant.find("texel") != std::string::npos;
                storage = storage || c.variant.find("storage-buffer") != std::string::npos;
            }
        CHECK((texel && storage));
    }
    CHECK(!r.device.limits.empty());
}

TEST_CASE("executor keep_all: every value readable, outputs unchanged", "[check]") {
    Graph g;
    int x = g.input("x", {7, 5});
    int a = ops::activation(g, ops::kActRelu, x, 0.01, "a");
    int b = ops::activation(g, ops::kActTanh, a, 0.01, "b");
    g.output(ops::binary(g, ops::Binary::Add, a, b, "c"), "y");
    TensorMap in{{"x", test::random_tensor({7, 5}, 3)}};
    GpuExecutor plain(test::gpu(), g, WeightStore{}), kept(test::gpu(), g, WeightStore{}, false, true);
    CHECK(kept.memory_plan().arena_bytes == kept.memory_plan().total_bytes);  // nothing shares bytes
    TensorMap want = plain.run(in), got = kept.run(in);
    CHECK(got.at("y").data == want.at("y").data);
    TensorMap cpu = run_cpu(g, WeightStore{}, in);
    HostTensor va = kept.value(a);
    for (size_t i = 0; i < va.data.size(); ++i) CHECK(va.data[i] == std::max(0.0f, in.at("x").data[i]));
    CHECK(kept.value(x).data == in.at("x").data);
    CHECK_THROWS(plain.value(a));
    test::require_no_validation_messages();
}
