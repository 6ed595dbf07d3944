// vtloc-bench-tactile [weights.safetensors]: the tactile encoder (ResNet-18 + MLP
// head, SPEC section 2) at 224 x 224 on the default device: median ms over 20
// runs, GFLOP/s (convolutions and linear layers, 2 FLOPs per multiply-add), that
// as a fraction of the fma probe measured in the same run, the slowest nodes,
// preprocessing of a 480 x 640 frame, and one run of the CPU reference.
// Without a weight file it uses random weights of the vtloc-r18 shapes (timing
// does not depend on the values).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "bench/clock.h"
#include "bench/flops.h"
#include "bench/probe.h"
#include "bench/random_weights.h"
#include "bench/validation.h"
#include "base/error.h"
#include "engine/executor.h"
#include "engine/model/tactile_encoder.h"
#include "engine/model/prepared_weights.h"
#include "engine/ops/conv2d.h"
#include "engine/ops/tactile_preprocess.h"
#include "runtime/context.h"

using namespace vtloc;

namespace {

// torchvision resnet18 names (minus fc) and the MLP head, He-initialised.
WeightStore random_weights(const nlohmann::json& json) {
    const ModelConfig cfg = ModelConfig::parse(json, "bench");
    const TactileConfig& c = cfg.tactile;
    WeightStore w;
    w.set_config(json);
    bench::RandomWeights r(w, 7);
    const std::string p = "tactile.backbone.";
    r.conv_bn(p + "conv1", p + "bn1", {c.widths[0], 3, 7, 7}, false);
    int64_t in = c.widths[0];
    for (size_t s = 0; s < 4; ++s)
        for (int64_t b = 0; b < c.blocks[s]; ++b) {
            const std::string m = p + "layer" + std::to_string(s + 1) + "." + std::to_string(b) + ".";
            if ((s > 0 && b == 0) || in != c.widths[s])
                r.conv_bn(m + "downsample.0", m + "downsample.1", {c.widths[s], in, 1, 1}, false);
            r.conv_bn(m + "conv1", m + "bn1", {c.widths[s], in, 3, 3}, false);
            r.conv_bn(m + "conv2", m + "bn2", {c.widths[s], c.widths[s], 3, 3}, false);
            in = c.widths[s];
        }
    std::vector<int64_t> sizes{in};
    sizes.insert(sizes.end(), c.mlp.begin(), c.mlp.end());
    sizes.push_back(cfg.C);
    r.mlp("tactile.mlp", sizes);
    return w;
}

}  // namespace

int main(int argc, char** argv) {
    using vtloc::bench::ms_since;
    try {
        rt::Context ctx;
        const WeightStore file = argc > 1 ? WeightStore::load(argv[1]) : random_weights(nlohmann::json::parse(bench::kR18Config));
        const ModelConfig cfg = config_of(file);
        const WeightStore w = prepare_weights(cfg, file);
        const int64_t S = cfg.tactile.in_size;
        std::printf("device: %s\nweights: %s\n", ctx.info().name.c_str(), argc > 1 ? argv[1] : "random, vtloc-r18 shapes");

        Graph g;
        int x = g.input("tactile.input", {1, 3, S, S});
        g.output(build_tactile_encoder(g, w, cfg, x), "tactile.feature");
        double flops = 0;  // conv2d and linear
        for (auto& [name, f] : bench::node_flops(g)) flops += f;
        TensorMap in{{"tactile.input", HostTensor({1, 3, S, S}, std::vector<float>(size_t(3 * S * S), 0.5f))}};

        auto t0 = std::chrono::steady_clock::now();
        GpuExecutor exec(ctx, g, w);
        exec.run(in);  // first run compiles the shaders (lavapipe compiles at first dispatch)
        std::printf("setup + first run (shader compilation): %.1f s\n", ms_since(t0) * 1e-3);

        // The probe right before and right after the timed runs; the higher one
        // counts, so a busy machine cannot flatter the ratio.
        const int reps = 20;
        const double probe_before = bench::peak_gflops(ctx);
        bench::Stats st = bench::summarize(bench::time_ms([&] { exec.run(in); }, 2, reps));
        const double probe_after = bench::peak_gflops(ctx);
        const double probe = std::max(probe_before, probe_after);
        const double gflops = flops / (st.median * 1e-3) * 1e-9;
        std::printf("encoder %lldx%lld: %.2f GFLOP (conv + linear), %u dispatches\n", (long long)S, (long long)S,
                    flops * 1e-9, exec.sequence().dispatch_count());
        std::printf("GPU: median %.2f ms over %d runs (p10 %.2f, p90 %.2f)\n", st.median, reps, st.p10, st.p90);
        std::printf("     %.1f GFLOP/s = %.0f%% of the fma probe (%.1f GFLOP/s: the higher of %.1f before and\n"
                    "     %.1f after the timed runs)\n",
                    gflops, 100.0 * gflops / probe, probe, probe_before, probe_after);

        GpuExecutor prof(ctx, g, w, /*profile=*/true);
        prof.run(in);
        std::vector<rt::Sequence::NodeTime> nodes;
        for (int i = 0; i < 5; ++i) {  // per node: the fastest of 5 runs
            prof.run(in);
            auto t = prof.node_times();
            if (nodes.empty()) nodes = t;
            for (size_t k = 0; k < t.size(); ++k) nodes[k].ms = std::min(nodes[k].ms, t[k].ms);
        }
        double all = 0;  // steadier than the wall median on a noisy host
        for (const auto& n : nodes) all += n.ms;
        std::sort(nodes.begin(), nodes.end(), [](auto& a, auto& b) { return a.ms > b.ms; });
        std::printf("all %zu nodes (profiled, each its best of 5): %.2f ms\n", nodes.size(), all);
        std::printf("slowest nodes (profiled, best of 5):\n");
        for (size_t i = 0; i < nodes.size() && i < 8; ++i) std::printf("  %7.2f ms  %s\n", nodes[i].ms, nodes[i].label.c_str());

        Graph pg;
        int img = pg.input("image", {480, 640, 3}, ElemType::I32);
        pg.output(add_tactile_preprocess(pg, cfg, img), "tactile.input");
        std::vector<uint8_t> frame(480 * 640 * 3, 128);
        TensorMap pin{{"image", ops::tactile_image_tensor(frame.data(), 480, 640)}};
        GpuExecutor pexec(ctx, pg, w);
        bench::Stats pst = bench::summarize(bench::time_ms([&] { pexec.run(pin); }, 2, reps));
        std::printf("preprocessing a 480x640 frame: median %.2f ms (upload included)\n", pst.median);

        t0 = std::chrono::steady_clock::now();
        run_cpu(g, w, in);
        std::printf("CPU reference (plain loops, one thread): %.0f ms for one run\n", ms_since(t0));
        bench::check_validation(ctx, "vtloc-bench-tactile");
    } catch (const Error& e) {
        std::fprintf(stderr, "vtloc-bench-tactile: %s\n", e.what());
        return 1;
    }
    return 0;
}
