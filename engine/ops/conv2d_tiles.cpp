// conv2d's tile choice (see engine/ops/conv2d.h and shaders/conv2d.glsl).
#include <algorithm>
#include <cmath>
#include <thread>

#include "engine/ops/common.h"
#include "engine/ops/conv2d.h"

namespace vtloc::ops {

uint32_t conv_window_shift(const ConvShape& s, uint32_t c) {
    // Block origins are multiples of c, and the last one is OW - c (see the shader).
    const bool same = s.w % 4 == 0 && (int64_t(c) * s.sw) % 4 == 0 && ((s.ow - int64_t(c)) * s.sw) % 4 == 0;
    return same ? uint32_t(((-s.pw) % 4 + 4) % 4) : 4u;
}

ConvTiles choose_conv_tiles(const rt::DeviceInfo& d, const ConvShape& s, bool vec4_weights, bool vec4_input) {
    const uint32_t sg = std::max(1u, d.subgroup_size);
    const uint32_t max_local = std::min(d.max_invocations, d.max_workgroup_size[0]);
    auto blocks = [](int64_t n, int64_t b) { return (n + b - 1) / b; };
    if (d.type != VK_PHYSICAL_DEVICE_TYPE_CPU) {
        // GPUs hide load latency with many threads: a small block, whole subgroups,
        // and enough workgroups for every compute unit. Blocks shrink until the
        // dispatch offers fill_workgroups(d); where even the smallest does not, the
        // input channels are split (at least 8 per part, at most 64 parts).
        const uint32_t local = std::min(elementwise_local_size(d), 128u);
        const uint64_t target = rt::fill_workgroups(d);
        const uint32_t blocks_tm_r_c[][3] = {{8, 2, 4}, {8, 2, 2}, {8, 1, 2}, {4, 1, 2}};
        auto groups = [&](uint32_t tm, uint32_t r, uint32_t c) {
            return uint64_t(blocks(s.n * blocks(s.cout, tm) * blocks(s.oh, r) * blocks(s.ow, c), local));
        };
        uint32_t tm = 4, r = 1, c = 1;
        for (const auto& b : blocks_tm_r_c) {
            tm = s.cout > 4 ? b[0] : 4u, r = uint32_t(std::min<int64_t>(b[1], s.oh)), c = uint32_t(std::min<int64_t>(b[2], s.ow));
            if (groups(tm, r, c) >= target) break;
        }
        const uint64_t g = groups(tm, r, c);
        const uint64_t most = uint64_t(std::clamp<int64_t>(s.cin / 8, 1, 64));
        const uint32_t ksplit = uint32_t(std::min(most, (target + g - 1) / g));
        return {tm, r, c, local, uint32_t(s.kh), conv_window_shift(s, c), std::max(1u, ksplit)};
    }
    // CPU devices run a subgroup as one SIMD instruction stream. What costs is
    // fetching: in fma units, measured on lavapipe, a texel fetch (a gather, one
    // float or one vec4 per lane) ~20, a storage-buffer store ~24 (~40 for a vec4).
    const double kFetch = 20, kStore = 24, kStepOverhead = 30;
    const double threads = std::max(1u, std::thread::hardware_concurrency());
    // Bounds on the unrolled shader. Its size costs compile time (lavapipe compiles
    // at the first dispatch: on a 3x3 kernel ~0.4 s for 128 accumulators, ~0.6 s
    // for 196, ~1.8 s for 392; 7x7 with 128: ~2 s), which only a big convolution
    // earns back.
    const double macs = double(s.n) * s.cout * s.cin * s.kh * s.kw * s.oh * s.ow;
    const uint32_t max_acc = macs >= 5e7 && s.kh * s.kw <= 9 ? 392 : 128;
    const double max_unrolled = std::clamp(macs / 2048, 512.0, 6272.0);
    // Kernels above 3x3 go one kernel row at a time (see KHB in the shader):
    // measured ~1.5x faster on the ResNet stem.
    const uint32_t khb = s.kh * s.kw > 9 ? 1 : uint32_t(s.kh);
    ConvTiles best{4, 1, 1, std::min(sg, max_local), khb, conv_window_shift(s, 1)};
    double best_time = -1;
    for (uint32_t tm : {16u, 8u, 4u}) {
        if (tm > 4 && tm > s.cout) continue;  // blocks fit inside the output (see the shader)
        for (uint32_t r = 1; r <= 8 && r <= s.oh; ++r)
            for (uint32_t c = 1; c <= 8 && c <= s.ow; ++c) {
                const double acc = tm * r * c, taps = double(khb) * s.kw;
                if (acc > max_acc || double(s.kh * s.kw) * acc > max_unrolled) continue;
                const double rows = double((r - 1) * s.sh + khb), cols = double((c - 1) * s.sw + s.kw);
                const uint32_t shift = conv_window_shift(s, c);
                // A per-invocation shift costs ~2 selects per column (~1 fma unit each).
                const double window = !vec4_input ? rows * cols * kFetch
                                      : shift < 4 ? rows * std::floor((shift + cols + 3) / 4) * kFetch
                                                  : rows * (std::floor((cols + 6) / 4) * kFetch + 2 * cols);
                const double wfetch = taps * (vec4_weights ? tm / 4 : tm);
                const double step = window + wfetch * kFetch + taps * acc + kStepOverhead;
                const bool yvec4 = vec4_input && s.ow % 4 == 0 && c % 4 == 0;  // as conv2d.cpp decides
                const double lane = double(s.cin) * double(s.kh / khb) * step + acc * (yvec4 ? 10 : kStore);
                const double lanes = double(s.n) * blocks(s.cout, tm) * blocks(s.oh, r) * blocks(s.ow, c);
                const double time = std::ceil(std::ceil(lanes / sg) / threads) * lane;
                if (best_time < 0 || time < best_time) best_time = time, best = {tm, r, c, best.local, khb, shift};
            }
    }
    // Measured on ResNet-18 at 224 (docs/performance.md, "Accumulators in groups"): with the
    // JIT held to AVX2 its nodes took ~7 % less time in groups of 4; with AVX-512's 32
    // registers, no clear difference either way. Grouped code compiles slower, so only big
    // convolutions (as for max_acc) earn it.
    const uint32_t regs = d.host_vector_registers;
    best.c_group = regs > 0 && regs <= 16 && macs >= 5e7 ? 4u : 1u;
    return best;
}

}  // namespace vtloc::ops
