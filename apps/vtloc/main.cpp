// vtloc: command-line front end of the engine.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <random>
#include <string>

#include "engine/error.h"
#include "engine/executor.h"
#include "engine/ops/common.h"
#include "runtime/context.h"

using namespace vtloc;

namespace {

const char* kUsage =
    "usage: vtloc <command> [options]\n"
    "\n"
    "commands:\n"
    "  demo      run a small MLP graph on the GPU and on the CPU reference and compare\n"
    "            (the VTLoc model replaces it once it lands)\n"
    "  devices   list Vulkan devices and the limits the engine uses\n"
    "\n"
    "environment:\n"
    "  VTLOC_DEVICE=<index|name>   pick a device (default: discrete > integrated > CPU)\n"
    "  VTLOC_VALIDATION=1          turn on the Khronos validation layer\n"
    "\n"
    "`vtloc <command> --help` describes one command.\n";

void print_device(const rt::DeviceInfo& d, bool chosen) {
    std::printf("%s[%u] %s (%s, Vulkan %u.%u)\n", chosen ? "* " : "  ", d.index, d.name.c_str(),
                rt::device_type_name(d.type), VK_API_VERSION_MAJOR(d.api_version),
                VK_API_VERSION_MINOR(d.api_version));
    std::printf("      subgroup %u, shared memory %u KiB, workgroup <= %u invocations, "
                "storage binding <= %llu MiB, %u storage buffers per stage, timestamps %s\n",
                d.subgroup_size, d.max_shared_memory / 1024, d.max_invocations,
                (unsigned long long)(d.max_storage_buffer_range >> 20), d.max_storage_buffers,
                d.has_timestamps ? "yes" : "no");
}

int cmd_devices(int argc, char** argv) {
    if (argc > 2 && (!std::strcmp(argv[2], "--help") || !std::strcmp(argv[2], "-h"))) {
        std::puts("usage: vtloc devices\n\nLists Vulkan devices; '*' marks the one the engine picks.");
        return 0;
    }
    auto devs = rt::Context::list_devices();
    rt::Context ctx;
    for (auto& d : devs) print_device(d, d.index == ctx.info().index);
    return 0;
}

int cmd_demo(int argc, char** argv) {
    if (argc > 2 && (!std::strcmp(argv[2], "--help") || !std::strcmp(argv[2], "-h"))) {
        std::puts("usage: vtloc demo\n\nBuilds a 3-layer MLP (seeded random weights), runs it on the\n"
                  "chosen Vulkan device and on the CPU reference, and prints both and their difference.");
        return 0;
    }
    rt::Context ctx;
    print_device(ctx.info(), true);

    const int64_t batch = 4, in = 32, hidden = 64, out = 3;
    std::mt19937 rng(7);
    auto random = [&](Shape s, float scale) {
        std::uniform_real_distribution<float> d(-scale, scale);
        HostTensor t(s);
        for (float& v : t.data) v = d(rng);
        return t;
    };
    WeightStore w;
    w.add("mlp.0.weight", random({hidden, in}, 0.2f));
    w.add("mlp.0.bias", random({hidden}, 0.1f));
    w.add("mlp.2.weight", random({hidden, hidden}, 0.15f));
    w.add("mlp.2.bias", random({hidden}, 0.1f));
    w.add("mlp.4.weight", random({out, hidden}, 0.15f));
    w.add("mlp.4.bias", random({out}, 0.1f));

    Graph g;
    int x = g.input("x", {batch, in});
    int h = g.add1("linear", {x, g.weight("mlp.0.weight", {hidden, in}), g.weight("mlp.0.bias", {hidden})},
                   {{"act", ops::kActRelu}}, "fc0");
    h = g.add1("linear", {h, g.weight("mlp.2.weight", {hidden, hidden}), g.weight("mlp.2.bias", {hidden})},
               {{"act", ops::kActRelu}}, "fc2");
    g.output(g.add1("tanh", {g.add1("linear", {h, g.weight("mlp.4.weight", {out, hidden}),
                                               g.weight("mlp.4.bias", {out})}, {}, "fc4")}, {}, "tanh"),
             "y");

    TensorMap inputs{{"x", random({batch, in}, 1.0f)}};
    GpuExecutor exec(ctx, g, w);
    auto t0 = std::chrono::steady_clock::now();
    TensorMap gpu = exec.run(inputs);
    auto t1 = std::chrono::steady_clock::now();
    TensorMap cpu = run_cpu(g, w, inputs);

    double max_diff = 0.0;
    for (int64_t b = 0; b < batch; ++b) {
        std::printf("row %lld  gpu", (long long)b);
        for (int64_t j = 0; j < out; ++j) std::printf(" % .6f", gpu["y"].data[size_t(b * out + j)]);
        std::printf("   cpu");
        for (int64_t j = 0; j < out; ++j) {
            size_t i = size_t(b * out + j);
            std::printf(" % .6f", cpu["y"].data[i]);
            max_diff = std::max(max_diff, double(std::abs(gpu["y"].data[i] - cpu["y"].data[i])));
        }
        std::printf("\n");
    }
    std::printf("max |gpu - cpu| = %.3g; GPU run %.3f ms (first submit); arena %llu bytes for %llu bytes "
                "of tensors\n",
                max_diff, std::chrono::duration<double, std::milli>(t1 - t0).count(),
                (unsigned long long)exec.memory_plan().arena_bytes,
                (unsigned long long)exec.memory_plan().total_bytes);
    if (!(max_diff <= 1e-4)) {
        std::fprintf(stderr, "vtloc: GPU and CPU disagree beyond 1e-4\n");
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
        !std::strcmp(argv[1], "help")) {
        std::fputs(kUsage, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    std::string cmd = argv[1];
    try {
        if (cmd == "demo") return cmd_demo(argc, argv);
        if (cmd == "devices") return cmd_devices(argc, argv);
        std::fprintf(stderr, "vtloc: unknown command '%s'\n\n%s", cmd.c_str(), kUsage);
        return 2;
    } catch (const Error& e) {
        std::fprintf(stderr, "vtloc: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vtloc: internal error: %s\n", e.what());
        return 3;
    }
}
