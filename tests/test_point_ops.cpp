// The point-cloud ops: FPS and ball query (indices exact: GPU = CPU reference =
// PyTorch reference), grouping, the fused PointNet++ MLP layer, the max over
// neighbours and cloud normalisation (fp32: the default 1e-4 + 1e-4*|ref|; the
// CPU GEMM accumulates in double, so this bounds the shader's fp32 rounding
// over K <= 70 terms of O(1)).
#include <catch2/catch.hpp>

#include <algorithm>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <unistd.h>
#include <random>

#include "base/error.h"
#include "base/python.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "engine/ops/point_common.h"
#include "engine/safetensors.h"
#include "runtime/spirv_reflect.h"
#include "shaders/shader_registry.h"
#include "tests/golden.h"
#include "tests/run_both.h"

using namespace vtloc;

namespace {

HostTensor cloud_tensor(const std::vector<float>& xyz, int64_t D = 3) {
    const int64_t N = int64_t(xyz.size()) / 3;
    HostTensor t({N, D});
    for (int64_t i = 0; i < N; ++i)
        for (int64_t k = 0; k < D; ++k) t.data[size_t(i * D + k)] = k < 3 ? xyz[size_t(3 * i + k)] : 0.1f * float(k + i % 5);
    return t;
}

HostTensor random_cloud(int64_t N, uint32_t seed, int64_t D = 3) {
    return test::random_tensor({N, D}, seed);
}

struct Scale {
    double radius;
    int64_t nsample;
};

// FPS then one ball query per scale, on the GPU and the CPU; returns both.
test::BothRuns fps_and_balls(const HostTensor& cloud, int64_t npoint, const std::vector<Scale>& scales,
                             bool no_registers = false, bool tree = false) {
    Graph g;
    int x = g.input("cloud", cloud.shape);
    std::vector<int> f = ops::fps(g, x, npoint, "fps", no_registers, tree);
    g.output(f[0], "fps");
    g.output(f[1], "centres");
    for (size_t s = 0; s < scales.size(); ++s)
        g.output(ops::ball_query(g, x, f[1], scales[s].radius, scales[s].nsample, "", tree), "ball." + std::to_string(s));
    return test::run_both(g, WeightStore{}, {{"cloud", cloud}});
}

// Both ways: subgroup operations where the device has them, and the shared-memory
// shaders (FPS's tree reduction, ball query's tiles).
void check_fps_and_balls(const HostTensor& cloud, int64_t npoint, const std::vector<Scale>& scales,
                         bool no_registers = false) {
  for (bool tree : {false, true}) {
    INFO("N " << cloud.shape[0] << " D " << cloud.shape[1] << " npoint " << npoint << " workspace path " << no_registers
              << " shared-memory shaders " << tree);
    test::BothRuns r = fps_and_balls(cloud, npoint, scales, no_registers, tree);
    test::require_same_ints(r.gpu.at("fps"), r.cpu.at("fps"), "fps");
    CHECK(r.gpu.at("centres").data == r.cpu.at("centres").data);
    for (size_t s = 0; s < scales.size(); ++s)
        test::require_same_ints(r.gpu.at("ball." + std::to_string(s)), r.cpu.at("ball." + std::to_string(s)), "ball");
  }
}

// The PyTorch reference's FPS and ball query on the cases of tests/point_cases.py,
// made once per build (8 s, nearly all of this test's time) and kept beside the
// paper goldens; made again when the script or the reference it runs
// (weights_tools/pointnet2.py) is newer. The script writes a file of this
// process's own, renamed into place: the sg4/ copy of the test may run at the
// same time. The interpreter: python_interpreter (as for vtloc-bench).
std::string point_cases_file() {
    namespace fs = std::filesystem;
    const fs::path cached = fs::path(test::build_goldens_dir()) / "point_cases.safetensors";
    const fs::path src = VTLOC_SOURCE_DIR;
    std::error_code ec;
    const fs::file_time_type made = fs::last_write_time(cached, ec);
    if (!ec && made > fs::last_write_time(src / "tests" / "point_cases.py") &&
        made > fs::last_write_time(src / "weights_tools" / "pointnet2.py"))
        return cached.string();
    fs::create_directories(cached.parent_path());
    const std::string path = cached.string() + "." + std::to_string(::getpid()) + ".tmp";
    const std::string python = python_interpreter(VTLOC_PYTHON);
    const std::string cmd = "cd '" VTLOC_SOURCE_DIR "' && PYTHONDONTWRITEBYTECODE=1 '" + python +
                            "' tests/point_cases.py '" + path + "'";
    INFO("writing the PyTorch reference cases: " << cmd);
    const int rc = std::system(cmd.c_str());
    if (rc != 0) fs::remove(path, ec);  // a failed run leaves no half-written file behind
    REQUIRE(rc == 0);
    fs::rename(path, cached);
    return cached.string();
}

}  // namespace

TEST_CASE("FPS and ball query equal the PyTorch reference on ties, duplicates, grids, 16..16384 points",
          "[op][fps][ball_query]") {
    const std::string file = point_cases_file();
    test::Golden cases(file);
    for (const char* name : {"random_1000", "duplicates", "identical", "collinear", "grid", "n16", "n17", "n4097",
                             "n16384"}) {
        INFO("case " << name);
        const std::string n = name;
        HostTensor params = cases.f32(n + ".params"), cloud = cases.f32(n + ".cloud");
        std::vector<Scale> scales;
        for (size_t i = 1; i + 1 < params.data.size(); i += 2) scales.push_back({params.data[i], int64_t(params.data[i + 1])});
        test::BothRuns r = fps_and_balls(cloud, int64_t(params.data[0]), scales);
        const std::vector<int32_t> fps = cases.i32(n + ".fps");
        CHECK(r.cpu.at("fps").ints() == fps);
        CHECK(r.gpu.at("fps").ints() == fps);
        for (size_t s = 0; s < scales.size(); ++s) {
            const std::string b = ".ball." + std::to_string(s);
            const std::vector<int32_t> ball = cases.i32(n + b);
            CHECK(r.cpu.at(b.substr(1)).ints() == ball);
            CHECK(r.gpu.at(b.substr(1)).ints() == ball);
        }
    }
}

TEST_CASE("FPS at every workgroup size picks the CPU reference's points", "[op][fps]") {
    // Param threads (the bench's variants, a GPU's choice to come): the registers
    // path at up to 32 points a thread, the workspace path past that, on a cloud with
    // ties (a grid, every point twice) and a random one; sizes the device cannot take
    // are refused by name.
    const rt::DeviceInfo& d = test::gpu().info();
    std::vector<float> grid;
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j)
            for (int k = 0; k < 5; ++k) grid.insert(grid.end(), {i * 0.5f, j * 0.5f, k * 0.25f});
    std::vector<float> twice = grid;
    twice.insert(twice.end(), grid.begin(), grid.end());
    for (const HostTensor& cloud : {cloud_tensor(twice), random_cloud(700, 81, 6)}) {
        const int64_t N = cloud.shape[0], S = 150;
        for (uint32_t threads = std::max(1u, d.subgroup_size); threads <= 256; threads *= 2) {
            INFO(N << " points, threads " << threads);
            Graph g;
            const int x = g.input("x", cloud.shape);
            const std::vector<int> f = ops::fps(g, x, S, "fps", false, false, threads);
            g.output(f[0], "index");
            g.output(f[1], "centres");
            const TensorMap out = test::run_gpu_and_compare(g, WeightStore{}, {{"x", cloud}});
            GpuExecutor ex(test::gpu(), g, WeightStore{});
            CHECK(ex.sequence().dispatch_log().at(0).spec.at(0) == threads);
        }
    }
    Graph g;
    const int x = g.input("x", {64, 3});
    REQUIRE_THROWS_WITH(ops::fps(g, x, 8, "three", false, false, 3), Catch::Contains("power of two"));
    if (d.max_invocations < 1024 || d.max_shared_memory / 16 < 1024) {
        g.output(ops::fps(g, x, 8, "big", false, false, 1024)[0], "i");
        REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g, WeightStore{}), Catch::Contains("'big'") && Catch::Contains("threads = 1024"));
    }
}

TEST_CASE("FPS and ball query match the CPU reference at odd sizes and widths", "[op][fps][ball_query]") {
    check_fps_and_balls(random_cloud(1000, 1), 1000, {{0.3, 16}});        // npoint = N, N not a power of two
    check_fps_and_balls(random_cloud(333, 2, 6), 100, {{0.2, 7}, {0.9, 64}});  // [N, 6]: xyz + normals
    check_fps_and_balls(random_cloud(5000, 3), 512, {{0.1, 32}});
    check_fps_and_balls(random_cloud(2000, 4), 300, {{0.4, 20}}, true);   // the workspace path (minima in memory)
    check_fps_and_balls(random_cloud(16384, 5), 64, {{2.0, 3}}, true);
    // A grid with ties everywhere, points shuffled, and duplicates of every point.
    std::vector<float> xyz;
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
            for (int k = 0; k < 7; ++k) xyz.insert(xyz.end(), {i * 0.5f, j * 0.5f, k * 0.25f});
    std::vector<float> twice = xyz;
    twice.insert(twice.end(), xyz.begin(), xyz.end());
    check_fps_and_balls(cloud_tensor(twice), 504, {{0.5, 9}, {0.25, 3}});
}

using Weights = ops::GroupLinear::Weights;
using Tile = ops::GroupLinear::Tile;
constexpr Weights kWeightPaths[] = {Weights::Shuffle, Weights::Uniform, Weights::Storage};
const char* weights_name(Weights w) { return w == Weights::Shuffle ? "shuffle" : w == Weights::Uniform ? "uniform" : "storage"; }

// Each weight path the tests ask for is the one that runs on this device (small
// weights at offset 0), so a sweep cannot pass on a fallback; where the device
// lacks shuffles the test says so.
void require_weight_path(Weights w) {
    const rt::DeviceInfo& d = test::gpu().info();
    const bool shuffles = ops::has_subgroup_shuffles(d) && (d.subgroup_ops & VK_SUBGROUP_FEATURE_VOTE_BIT);
    INFO("device " << d.name << ", subgroup shuffles " << shuffles);
    CHECK(ops::group_linear_weight_path(d, 40, 64, true, w, 0) == (w == Weights::Shuffle && !shuffles ? Weights::Uniform : w));
    CHECK(ops::group_linear_weight_path(d, 40, 64, false, w, 0) == Weights::Storage);
}

TEST_CASE("point grouping, the fused MLP layers and the neighbour max match the CPU reference", "[op][group_linear][point_group][group_max]") {
    for (bool normals : {true, false})
      for (ops::BufferPath path : ops::kBufferPaths)
      for (Weights ubo : kWeightPaths) {
        if (path == ops::BufferPath::Storage && ubo != Weights::Shuffle) continue;  // it reads storage buffers only
        INFO("features " << normals << ", " << ops::path_name(path) << ", weights " << weights_name(ubo));
        const int64_t N = 300, S = 37, ns = 12, C1 = 20, C2 = 33, C3 = 24;
        const int64_t K = normals ? 6 : 3;
        WeightStore w;
        auto add = [&](const std::string& name, Shape s, uint32_t seed, float r) {
            HostTensor t = test::random_tensor(s, seed, -r, r);
            if (s.size() == 2) w.add(name + "t", ops::point_weight_kn(t));  // group_linear's [in, out]
            w.add(name, std::move(t));
        };
        add("w1", {C1, K}, 11, 0.5f);
        add("b1", {C1}, 12, 0.2f);
        add("w2", {C2, C1}, 13, 0.3f);
        add("b2", {C2}, 14, 0.2f);
        add("w3", {C3, 3 + C1}, 15, 0.3f);
        add("b3", {C3}, 16, 0.2f);
        Graph g;
        int x = g.input("cloud", {N, 6});
        std::vector<int> f = ops::fps(g, x, S);
        int ball = ops::ball_query(g, x, f[1], 0.6, ns);
        int w1 = g.weight("w1", {C1, K}), b1 = g.weight("b1", {C1}), w2 = g.weight("w2", {C2, C1}), b2 = g.weight("b2", {C2});
        int w1t = g.weight("w1t", {K, C1}), w2t = g.weight("w2t", {C1, C2}), w3 = g.weight("w3", {C3, 3 + C1}),
            w3t = g.weight("w3t", {3 + C1, C3}), b3 = g.weight("b3", {C3});
        const ops::Act relu = ops::kActRelu;
        std::vector<int> gin{x, f[1], ball};
        if (normals) gin.push_back(x);
        if (path == ops::BufferPath::Texel) require_weight_path(ubo);
        // Unfused: point_group, linear, linear, group_max.
        int grouped = ops::point_group(g, gin, 3);
        g.output(grouped, "grouped");
        int h = ops::linear(g, grouped, w1, b1, relu);
        int y = ops::linear(g, h, w2, b2, relu);
        g.output(ops::group_max(g, y, ns, false), "unfused");
        // Fused: gather in the first layer, max in the last; and both in one layer.
        using In = ops::GroupLinear::Input;
        std::vector<int> fin{x, f[1], ball, w1t, b1};
        if (normals) fin.push_back(x);
        int fh = ops::group_linear(g, fin, ops::GroupLinear{In::Gather, 3, false, 1, relu, 0.01, path, ubo});
        g.output(fh, "first");  // channel-major [C1, S * ns]
        g.output(ops::group_max(g, fh, ns, true), "max_cm");
        g.output(ops::group_max(g, h, ns, false), "max_pm");
        g.output(ops::group_linear(g, {fh, w2t, b2}, ops::GroupLinear{In::Rows, 0, true, ns, relu, 0.01, path, ubo}), "fused");
        int one = ops::group_linear(g, fin, ops::GroupLinear{In::Gather, 3, true, 1, relu, 0.01, path, ubo});
        g.output(one, "one_layer");
        // Group all: [xyz, features] -> layer -> max over all S rows, fused and not.
        g.output(ops::group_linear(g, {f[1], w3t, b3, one},
                                   ops::GroupLinear{In::GroupAll, 0, true, S, ops::kActNone, 0.01, path, ubo}),
                 "all");
        int cat = ops::concat(g, {f[1], one});
        g.output(ops::group_max(g, ops::linear(g, cat, w3, b3), S, false), "all_unfused");
        TensorMap out = test::run_gpu_and_compare(g, w, {{"cloud", random_cloud(N, 21, 6)}});
        test::require_close(out.at("fused"), out.at("unfused"), {}, "fused = unfused");
        test::require_close(out.at("all"), out.at("all_unfused"), {}, "group all fused = unfused");
        test::require_close(out.at("max_cm"), out.at("max_pm"), {}, "group_max channel-major = point-major");
        CHECK(out.at("first").shape == Shape{C1, S * ns});
        CHECK(out.at("one_layer").shape == Shape{S, C1});
        CHECK(out.at("all").shape == Shape{1, C3});
    }
}

namespace {

struct FusedCase {
    int64_t M, K, N, group;
};

// What a sweep covers. The README's command leaves out the 16 x 32 tile (tests and
// comparisons only: no device picks it, and its unrolled shader is the slowest to
// compile), and with `pairs` each layer variant (buffer path, weight path, tile)
// runs half its output modes on one case and the other half on the next, taking
// turns: every pair of factors (variant and mode, variant and case, mode and case)
// still meets, for half the pipelines (a cold lavapipe compiles each for ~1 s). It
// also leaves out the big-layer tiles on storage buffers: a CPU device reads its
// layers as texel buffers (storage only past the texel-buffer limit), and those
// pipelines compile for ~1.7 s each with an AVX2 JIT. The long suite runs the
// whole product.
struct Sweep {
    std::vector<Tile> tiles{Tile::Auto, Tile::Big8x32};
    std::vector<Weights> weights{std::begin(kWeightPaths), std::end(kWeightPaths)};
    bool pairs = true;
    std::vector<ops::BufferPath> paths{std::begin(ops::kBufferPaths), std::end(ops::kBufferPaths)};
    bool big_on_storage = false;  // the tiles asked on storage buffers too (else Auto there)
    // once_over = n (the quick sweeps, n cases): each variant runs one mode set on one
    // case, variant v set (v / n + v) % 2 on case v % n, so that over four variants or
    // more every set meets every case, and over two both sets run. Every pipeline a
    // variant compiles is one more for a cold lavapipe (~0.3 s, ~0.1 s from its disk
    // cache): the command runs each variant once, the long suite every set on every case.
    size_t once_over = 0;
    bool takes(ops::BufferPath path, Tile tile) const {
        return test::sweep_takes_tile(path, tile, big_on_storage);
    }
    // Mode set `set` (0 or 1) runs on variant v of case k: with pairs they alternate.
    bool runs(size_t v, size_t k, int set) const {
        if (once_over > 0) return k == v % once_over && (v / once_over + v) % 2 == size_t(set);
        return !pairs || (v + k) % 2 == size_t(set);
    }
};
// Over two cases or more, every variant ran both mode sets (one case alone pairs its
// variants with the modes by turns); run once each (once_over), one set each and both
// sets over the variants.
void require_both_sets(const std::map<std::string, int>& sets_run, size_t cases, const Sweep& sweep) {
    if (sweep.once_over > 0) {
        REQUIRE(cases == sweep.once_over);
        int any = 0;
        for (const auto& [on, bits] : sets_run) {
            INFO("variant " << on);
            CHECK((bits == 1 || bits == 2));
            any |= bits;
        }
        CHECK((any == 3 || sets_run.size() < 2));
        return;
    }
    if (cases < 2) return;
    for (const auto& [on, bits] : sets_run) {
        INFO("variant " << on);
        CHECK(bits == 3);
    }
}
// The quick sweeps' variants over their n cases, each once (Sweep::once_over).
Sweep once_each(Sweep s, size_t n) {
    s.once_over = n;
    return s;
}

// Every tile, weight path and buffer path; the mode sets take turns over the shapes
// (pairs), as in the quick sweeps: each variant runs both over the 4-5 full-size shapes.
// Every set on every shape compiled twice the pipelines, cold on CI's fresh machine:
// long/point_ops was 307-457 s there, the long suite's longest test.
const Sweep kEveryTile{{Tile::Auto, Tile::Big16x32, Tile::Big8x32},
                       {std::begin(kWeightPaths), std::end(kWeightPaths)},
                       true,
                       {std::begin(ops::kBufferPaths), std::end(ops::kBufferPaths)},
                       true};
// The variants whose shader depends on the subgroup size (test::subgroup_shader_variant;
// point_mlp_shfl: weights shared by shuffles, ball padding skipped by votes and pooled
// chunks), each tile. The README's subgroup-4 run sweeps these only; the other shaders
// hold no subgroup operation, and their subgroup-4 sweep is the long suite's.
const Sweep kSubgroupShader{{Tile::Auto, Tile::Big8x32}, {Weights::Shuffle}, true, {ops::BufferPath::Texel}};

// the fused MLP layer handles wide layers, large groups and ragged shapes: the cases given.
void fused_mlp_cases(std::initializer_list<FusedCase> cases, const Sweep& sweep = {}) {
    // Paper-like (128 neighbours, K = 131); a group size that is not a multiple of
    // 4 (scalar row loads); odd M, K, N (partial blocks, scalar weight loads).
    // 128 x 160 weights (80 KiB) exceed lavapipe's 64 KiB uniform range: the uniform path falls back.
    std::map<std::string, int> sets_run;  // per variant, which mode sets ran (bits), over all cases
    size_t k = 0;
    for (FusedCase c : cases) {
        WeightStore w;
        w.add("w", test::random_tensor({c.K, c.N}, 31, -0.15f, 0.15f));
        w.add("b", test::random_tensor({c.N}, 32, -0.1f, 0.1f));
        Graph g;
        int x = g.input("x", {c.K, c.M}), xt = g.input("xt", {c.M, c.K});  // xt: the same rows point-major
        int wv = g.weight("w", {c.K, c.N}), bv = g.weight("b", {c.N});
        using In = ops::GroupLinear::Input;
        struct Same {
            std::string got, want;
            bool transposed;
        };
        std::vector<Same> same;  // outputs that must equal others bit for bit
        size_t variants = 0;
        for (ops::BufferPath path : sweep.paths)
            for (Weights ubo : sweep.weights)
                // The device's tile for this size, and CPU devices' big-layer tiles.
                for (Tile tile : sweep.tiles) {
                    if (path == ops::BufferPath::Storage && ubo != Weights::Shuffle) continue;
                    // A tile is the same code on every weight path; 8 x 32 on the one CPU devices take.
                    if (tile != Tile::Auto && ubo == Weights::Uniform) continue;
                    if (tile == Tile::Big8x32 && ubo != Weights::Shuffle) continue;
                    if (tile != Tile::Auto && !test::big_tiles_apply()) continue;
                    if (!sweep.takes(path, tile)) continue;
                    if (path == ops::BufferPath::Texel) require_weight_path(ubo);
                    const std::string on = std::string(".") + ops::path_name(path) + "." + weights_name(ubo) +
                                           (tile == Tile::Big16x32 ? ".big" : tile == Tile::Big8x32 ? ".big8" : "");
                    // Set 0: the maxes; set 1: the plain outputs. The rows point-major (x [M, K]) give
                    // the same sums in the same order, so the same bits as the channel-major
                    // outputs (out [M, N]: transposed); each twin runs in its original's set.
                    const bool maxes = sweep.runs(variants, k, 0), plains = sweep.runs(variants, k, 1);
                    sets_run[on] |= (maxes ? 1 : 0) | (plains ? 2 : 0);
                    if (maxes) {
                        g.output(ops::group_linear(g, {x, wv, bv}, {In::Rows, 0, true, c.group, ops::kActRelu, 0.01, path, ubo, tile}),
                                 "max_relu" + on);
                        g.output(ops::group_linear(g, {x, wv, bv}, {In::Rows, 0, true, c.group, ops::kActNone, 0.01, path, ubo, tile}),
                                 "max" + on);  // negative maxima
                        ops::GroupLinear pm{In::Rows, 0, true, c.group, ops::kActRelu, 0.01, path, ubo, tile};
                        pm.x_point_major = true;
                        g.output(ops::group_linear(g, {xt, wv, bv}, pm), "max_relu.pm" + on);
                        same.push_back({"max_relu.pm" + on, "max_relu" + on, false});
                    }
                    if (plains) {
                        g.output(ops::group_linear(g, {x, wv, bv}, {In::Rows, 0, false, 1, ops::kActLeaky, 0.1, path, ubo, tile}),
                                 "plain" + on);
                        ops::GroupLinear pm{In::Rows, 0, false, 1, ops::kActLeaky, 0.1, path, ubo, tile};
                        pm.x_point_major = true;
                        g.output(ops::group_linear(g, {xt, wv, bv}, pm), "plain.pm" + on);
                        same.push_back({"plain.pm" + on, "plain" + on, false});
                        pm.point_major = true;
                        g.output(ops::group_linear(g, {xt, wv, bv}, pm), "plain.pm_out" + on);
                        same.push_back({"plain.pm_out" + on, "plain" + on, true});
                        pm.x_point_major = false;  // channel-major in, point-major out (after sa_gather)
                        g.output(ops::group_linear(g, {x, wv, bv}, pm), "plain.cm_in.pm_out" + on);
                        same.push_back({"plain.cm_in.pm_out" + on, "plain" + on, true});
                    }
                    ++variants;
                    if (tile != Tile::Auto) continue;
                    // The other workgroup grid: row blocks along x.
                    ops::GroupLinear rx{In::Rows, 0, true, c.group, ops::kActRelu, 0.01, path, ubo, tile};
                    rx.rows_in_x = true;
                    if (maxes) g.output(ops::group_linear(g, {x, wv, bv}, rx), "max_relu.rows_in_x" + on);
                    rx.max = false, rx.group = 1;
                    if (plains) g.output(ops::group_linear(g, {x, wv, bv}, rx), "plain.rows_in_x" + on);
                }
        INFO("M " << c.M << " K " << c.K << " N " << c.N << " group " << c.group);
        const HostTensor xv = test::random_tensor({c.K, c.M}, 33);
        const TensorMap out = test::run_gpu_and_compare(g, w, {{"x", xv}, {"xt", test::transposed(xv)}});
        for (const Same& p : same) {
            INFO(p.got);
            CHECK(out.at(p.got).data == (p.transposed ? test::transposed(out.at(p.want)) : out.at(p.want)).data);
        }
        // Texel buffers: each weight path asked, the 16 x 32 tile on all but uniform
        // weights, 8 x 32 on shuffled ones; storage buffers: shuffled weights on each tile
        // asked. Big tiles on CPU devices only. Twins: 1 on a variant's max set, 3 on its
        // plain set; with pairs, variants 0, 2, 4, ... run the maxes on even cases.
        const auto asked = [](const auto& list, auto v) { return size_t(std::count(list.begin(), list.end(), v)); };
        const size_t W = sweep.weights.size(), S = asked(sweep.weights, Weights::Shuffle),
                     U = asked(sweep.weights, Weights::Uniform);
        const size_t t16 = test::big_tiles_apply() ? asked(sweep.tiles, Tile::Big16x32) : 0,
                     t8 = test::big_tiles_apply() ? asked(sweep.tiles, Tile::Big8x32) : 0;
        const size_t texel = asked(sweep.paths, ops::BufferPath::Texel), storage = asked(sweep.paths, ops::BufferPath::Storage);
        CHECK(variants == texel * (W + t16 * (W - U) + t8 * S) + storage * S * (1 + (sweep.big_on_storage ? t16 + t8 : 0)));
        size_t max_sets = 0, plain_sets = 0;  // as Sweep::runs deals them on this case
        for (size_t v = 0; v < variants; ++v) max_sets += sweep.runs(v, k, 0), plain_sets += sweep.runs(v, k, 1);
        CHECK(same.size() == max_sets + 3 * plain_sets);
        ++k;
    }
    require_both_sets(sets_run, cases.size(), sweep);
}

}  // namespace

TEST_CASE("group_linear's tiles shrunk as a big GPU's are (forced) match the CPU reference", "[op][group_linear]") {
    // On a GPU a layer of few rows or channels shrinks its workgroups to one subgroup, its
    // channel block to 4, then its row block to 4, until the dispatch offers enough
    // workgroups (group_linear.cpp). Param fill forces that rule here: every input mode, a
    // max, ball padding skipped, the hidden layers and point-major rows, at the smallest
    // tiles (fill 2^20) and part way (fill 40), on every binding path the GPU takes.
    using In = ops::GroupLinear::Input;
    using Hidden = ops::GroupLinear::Hidden;
    const int64_t N = 200, S = 21, ns = 12, C1 = 20, C2 = 36;
    WeightStore w;
    w.add("w0t", test::random_tensor({6, 16}, 41, -0.5f, 0.5f));  // gathered rows: 3 features + xyz
    w.add("b0", test::random_tensor({16}, 42, -0.2f, 0.2f));
    w.add("w1t", test::random_tensor({16, C1}, 43, -0.4f, 0.4f));
    w.add("b1", test::random_tensor({C1}, 44, -0.2f, 0.2f));
    w.add("w2t", test::random_tensor({C1, C2}, 45, -0.3f, 0.3f));
    w.add("b2", test::random_tensor({C2}, 46, -0.2f, 0.2f));
    w.add("wat", test::random_tensor({3 + C1, C1}, 47, -0.3f, 0.3f));  // group all: xyz + the SA layer's C1
    w.add("wpt", test::random_tensor({6, 16}, 48, -0.5f, 0.5f));  // per point: 3 features + xyz
    const rt::DeviceInfo& d = test::gpu().info();
    const uint32_t sg = std::max(1u, d.subgroup_size);
    for (ops::BufferPath path : ops::kBufferPaths)
        for (int64_t fill : {int64_t(1) << 20, int64_t(40)}) {
            INFO(ops::path_name(path) << ", fill " << fill);
            Graph g;
            const int x = g.input("cloud", {N, 6});
            const std::vector<int> f = ops::fps(g, x, S);
            const int ball = ops::ball_query(g, x, f[1], 0.5, ns);
            auto layer = [&](In in, bool max, int64_t group) {
                ops::GroupLinear l{in, 3, max, group, ops::kActRelu, 0.01, path, Weights::Shuffle};
                l.fill = fill;
                return l;
            };
            const int w0t = g.weight("w0t", {6, 16}), b0 = g.weight("b0", {16}), w1t = g.weight("w1t", {16, C1}),
                      b1 = g.weight("b1", {C1}), w2t = g.weight("w2t", {C1, C2}), b2 = g.weight("b2", {C2});
            // The first layer from the gathered rows in registers, ball padding skipped.
            ops::GroupLinear first = layer(In::Gather, false, 1);
            first.hidden = Hidden::Gathered, first.skip_padding = true, first.point_major = true;
            const int h = ops::group_linear(g, {x, f[1], ball, w0t, b0, w1t, b1, x}, first, "first");
            ops::GroupLinear mx = layer(In::Rows, true, ns);
            mx.skip_padding = true, mx.x_point_major = true;
            g.output(ops::group_linear(g, {h, w2t, b2, ball}, mx, "max"), "max");
            // Plain rows channel-major, and a gathering layer that is its own max.
            const int hc = ops::group_linear(g, {x, f[1], ball, w0t, b0, x}, layer(In::Gather, false, 1), "gather");
            g.output(ops::group_linear(g, {hc, w1t, b1}, layer(In::Rows, false, 1), "plain"), "plain");
            const int one = ops::group_linear(g, {x, f[1], ball, w0t, b0, x}, layer(In::Gather, true, 1), "one");
            g.output(one, "one");
            // Per point, then its rows gathered (PerPoint), and a group-all layer.
            ops::GroupLinear pp = layer(In::Points, false, 1);
            pp.point_major = true;
            const int u = ops::group_linear(g, {x, g.weight("wpt", {6, 16}), b0, x}, pp, "points");
            ops::GroupLinear second = layer(In::Gather, true, 1);
            second.hidden = Hidden::PerPoint;
            g.output(ops::group_linear(g, {u, f[1], ball, g.weight("wpt", {6, 16}), w1t, b1}, second, "per_point"), "per_point");
            const int all_in = ops::group_linear(g, {x, f[1], ball, w0t, b0, w1t, b1, x}, [&] {
                ops::GroupLinear l = layer(In::Gather, true, 1);
                l.hidden = Hidden::Gathered;
                return l;
            }(), "sa");
            g.output(ops::group_linear(g, {f[1], g.weight("wat", {3 + C1, C1}), b1, all_in}, layer(In::GroupAll, true, S), "all"),
                     "all");
            test::run_gpu_and_compare(g, w, {{"cloud", random_cloud(N, 49, 6)}});
            // What ran: whole subgroups, tiles of multiples of 4; at 2^20 the smallest.
            GpuExecutor ex(test::gpu(), g, w);
            int layers = 0;
            for (const auto& r : ex.sequence().dispatch_log()) {
                if (r.shader.rfind("point_mlp", 0) != 0) continue;
                ++layers;
                INFO(r.node << ": L " << r.spec[0] << " TM " << r.spec[1] << " TN " << r.spec[2] << ", groups "
                            << r.groups[0] << " x " << r.groups[1]);
                CHECK(r.spec[0] % sg == 0);
                CHECK(r.spec[1] % 4 == 0);
                CHECK(r.spec[2] % 4 == 0);
                if (fill > 1000) {
                    CHECK(r.spec[0] == sg);
                    CHECK(r.spec[2] == 4);
                    CHECK(r.spec[1] == (r.spec[4] != 0 ? 8u : 4u));  // a max keeps its row block (a loop)
                } else {
                    CHECK((uint64_t(r.groups[0]) * r.groups[1] >= uint64_t(fill) || (r.spec[0] == sg && r.spec[2] == 4)));
                }
            }
            CHECK(layers == 9);
        }
}

TEST_CASE("a max's groups split across lanes (parts) give the same bits as one lane each", "[op][group_linear]") {
    // A GPU's rule gives a max's groups 2, 4, ... lanes when a layer has few groups
    // (point_mlp.glsl PARTS); forced here on lavapipe: every power of two up to the
    // subgroup size, groups of 128 rows (16 chunks) and of 13 (2 chunks: past 2 parts
    // some lanes have none), rows with ball padding skipped and a gathering layer.
    const rt::DeviceInfo& d = test::gpu().info();
    if (!(d.subgroup_ops & VK_SUBGROUP_FEATURE_SHUFFLE_BIT) || !(d.subgroup_ops & VK_SUBGROUP_FEATURE_VOTE_BIT))
        FAIL("lavapipe has subgroup shuffles and votes: this test needs them");
    using In = ops::GroupLinear::Input;
    const int64_t N = 400, C1 = 24, C2 = 20;
    WeightStore w;
    w.add("w0t", test::random_tensor({6, C1}, 71, -0.5f, 0.5f));
    w.add("b0", test::random_tensor({C1}, 72, -0.2f, 0.2f));
    w.add("w1t", test::random_tensor({C1, C2}, 73, -0.4f, 0.4f));
    w.add("b1", test::random_tensor({C2}, 74, -0.2f, 0.2f));
    const TensorMap in{{"cloud", random_cloud(N, 75, 6)}};
    for (int64_t ns : {int64_t(128), int64_t(13)}) {
        std::map<std::string, HostTensor> first;
        for (uint32_t parts = 1; parts <= d.subgroup_size; parts *= 2) {
            INFO("group " << ns << ", parts " << parts);
            Graph g;
            const int x = g.input("cloud", {N, 6});
            // 21 centres: the max layer's rows (21 x 128 x 24) fit Vulkan's minimum texel limit,
            // so a device that allows no more still takes the shuffle shader (VTLOC_MAX_TEXEL_ELEMENTS).
            const std::vector<int> f = ops::fps(g, x, 21);
            const int ball = ops::ball_query(g, x, f[1], 0.3, ns);  // small radius: padded balls
            const int w0t = g.weight("w0t", {6, C1}), b0 = g.weight("b0", {C1});
            const int w1t = g.weight("w1t", {C1, C2}), b1 = g.weight("b1", {C2});
            ops::GroupLinear rows{In::Gather, 3, false, 1, ops::kActRelu, 0.01, ops::BufferPath::Texel, Weights::Shuffle};
            rows.skip_padding = true;
            const int h = ops::group_linear(g, {x, f[1], ball, w0t, b0, x}, rows, "rows");
            ops::GroupLinear mx{In::Rows, 0, true, ns, ops::kActRelu, 0.01, ops::BufferPath::Texel, Weights::Shuffle};
            mx.skip_padding = true, mx.parts = parts;
            g.output(ops::group_linear(g, {h, w1t, b1, ball}, mx, "max"), "max");
            ops::GroupLinear gm{In::Gather, 3, true, 1, ops::kActLeaky, 0.1, ops::BufferPath::Texel, Weights::Shuffle};
            gm.parts = parts;
            g.output(ops::group_linear(g, {x, f[1], ball, w0t, b0, x}, gm, "gather_max"), "gather_max");
            const TensorMap out = test::run_gpu_and_compare(g, w, in);
            GpuExecutor ex(test::gpu(), g, w);
            for (const auto& r : ex.sequence().dispatch_log())
                if (r.node == "max" || r.node == "gather_max") CHECK(r.spec.at(18) == parts);
            for (const char* name : {"max", "gather_max"}) {
                if (parts == 1) first[name] = out.at(name);
                else CHECK(out.at(name).data == first.at(name).data);
            }
        }
    }
    // Refused by name: not a power of two, not a max, wider than a subgroup.
    Graph g;
    const int x = g.input("cloud", {N, 6});
    const int w1t = g.weight("w1t", {C1, C2}), b1 = g.weight("b1", {C2});
    const int rows = g.input("rows", {C1, 64});
    ops::GroupLinear l{In::Rows, 0, true, 16, ops::kActNone, 0.01, ops::BufferPath::Texel, Weights::Shuffle};
    l.parts = 3;
    REQUIRE_THROWS_WITH(ops::group_linear(g, {rows, w1t, b1}, l, "three"), Catch::Contains("power of two"));
    l.max = false, l.group = 1, l.parts = 2;
    REQUIRE_THROWS_WITH(ops::group_linear(g, {rows, w1t, b1}, l, "plain"), Catch::Contains("max = 1"));
    l.max = true, l.group = 16, l.parts = int64_t(d.subgroup_size) * 2;
    g.output(ops::group_linear(g, {rows, w1t, b1}, l, "wide"), "wide");
    (void)x;
    REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g, w), Catch::Contains("'wide'") && Catch::Contains("subgroup size"));
}

TEST_CASE("the fused MLP layer handles wide layers, large groups and ragged shapes", "[op][group_linear][sweep]") {
    // Every path but the 16 x 32 tile and the big tile on storage buffers (Sweep), each
    // once (Sweep::once_over): its maxes or its plain outputs on one of two shapes, groups
    // of 128 with vec4 rows or odd sizes with a group not a multiple of 4 (scalar loads,
    // partial blocks); 80 KiB weights (128 x 160) on the uniform path it falls back from.
    // A cold lavapipe spends most of this test compiling, so the long suite runs every
    // set of every path on every full-size shape, and every tile.
    fused_mlp_cases({FusedCase{2 * 128, 131, 96, 128}, FusedCase{1001, 37, 37, 13}}, once_each({}, 2));
    fused_mlp_cases({FusedCase{48, 128, 160, 16}}, Sweep{{Tile::Auto}, {Weights::Uniform}, false});
}

TEST_CASE("the fused MLP layer's subgroup shader handles wide layers, large groups and ragged shapes",
          "[op][group_linear][subgroup_sweep]") {
    // The sweep above on the variants that depend on the subgroup size (kSubgroupShader),
    // for the README's subgroup-4 run.
    fused_mlp_cases({FusedCase{2 * 128, 131, 96, 128}, FusedCase{1001, 37, 37, 13}}, once_each(kSubgroupShader, 2));
}

TEST_CASE("of the point-MLP layer variants, only the subgroup shader's hold subgroup operations", "[op][group_linear]") {
    // The README's subgroup-4 run sweeps test::subgroup_shader_variant's variants only,
    // on the premise that no other variant's shader depends on the subgroup size. The
    // SPIR-V of every variant the sweeps take says whether it does (a GroupNonUniform*
    // capability, rt::reflect_spirv).
    const auto subgroup_ops = [](const std::string& shader) {
        return rt::reflect_spirv(rt::find_spirv(shader), shader).subgroup_ops;
    };
    WeightStore w;
    w.add("w", test::random_tensor({20, 24}, 91));
    w.add("b", test::random_tensor({24}, 92));
    Graph g;
    const int x = g.input("x", {20, 64});
    const int wv = g.weight("w", {20, 24}), bv = g.weight("b", {24});
    using In = ops::GroupLinear::Input;
    std::map<std::string, bool> swept_at_4;  // node -> test::subgroup_shader_variant
    for (ops::BufferPath path : ops::kBufferPaths)
        for (Weights ubo : kWeightPaths)
            for (Tile tile : {Tile::Auto, Tile::Big8x32}) {
                if (path == ops::BufferPath::Storage && ubo != Weights::Shuffle) continue;
                if (tile != Tile::Auto && (ubo != Weights::Shuffle || !test::big_tiles_apply())) continue;
                if (path == ops::BufferPath::Texel) require_weight_path(ubo);
                const std::string node = std::string(ops::path_name(path)) + "." + weights_name(ubo) + (tile == Tile::Auto ? "" : ".big8");
                swept_at_4[node] = test::subgroup_shader_variant(path, ubo);
                // kSubgroupShader, which the fused and hidden sweeps take, names the same variants.
                const auto& p = kSubgroupShader.paths;
                const auto& ws = kSubgroupShader.weights;
                CHECK((std::count(p.begin(), p.end(), path) > 0 && std::count(ws.begin(), ws.end(), ubo) > 0) == swept_at_4[node]);
                g.output(ops::group_linear(g, {x, wv, bv}, {In::Rows, 0, true, 8, ops::kActRelu, 0.01, path, ubo, tile}, node), node);
            }
    GpuExecutor ex(test::gpu(), g, w);
    size_t seen = 0;
    for (const auto& r : ex.sequence().dispatch_log()) {
        if (!swept_at_4.count(r.node)) continue;
        ++seen;
        INFO(r.node << ": " << r.shader);
        CHECK(subgroup_ops(r.shader) == swept_at_4.at(r.node));
    }
    CHECK(seen == swept_at_4.size());
}

// The full-size sweeps' subgroup-dependent variants (every tile), for the long suite's
// subgroup-4 run: the other variants hold no subgroup operation (checked above), and
// their full-size sweep at subgroup 4 repeated the one at 8 (long/sg4/point_ops took
// 184 s cold in CI's run of 2026-12-05).
const Sweep kSubgroupShaderEveryTile{{Tile::Auto, Tile::Big16x32, Tile::Big8x32}, {Weights::Shuffle}, true, {ops::BufferPath::Texel}, true};

// The full-size shapes, one list for both sweeps.
static void fused_mlp_full_size(const Sweep& sweep) {
    fused_mlp_cases({FusedCase{20 * 128, 131, 96, 128}, FusedCase{2560, 64, 200, 5}, FusedCase{1001, 37, 37, 13}, FusedCase{36, 8, 8, 12},
                     FusedCase{640, 128, 160, 16}},
                    sweep);
}

TEST_CASE("the fused MLP layer handles wide layers, large groups and ragged shapes, at full size", "[long][group_linear]") {
    fused_mlp_full_size(kEveryTile);
}

TEST_CASE("the fused MLP layer's subgroup shader handles wide layers, large groups and ragged shapes, at full size",
          "[long][group_linear][subgroup_sweep]") {
    fused_mlp_full_size(kSubgroupShaderEveryTile);
}

TEST_CASE("group_linear's big-layer tile and its workgroup grid", "[op][group_linear]") {
    // A layer with rows for 128 invocations and 1.3e8 multiply-adds (a big layer
    // on CPU devices) and a small one; the tile is spec constants 1 (rows) and 2
    // (channels) of the dispatch. Recording is enough: nothing runs.
    const rt::DeviceInfo& d = test::gpu().info();
    WeightStore w;
    w.add("w", test::random_tensor({128, 64}, 3));
    w.add("b", test::random_tensor({64}, 4));
    Graph g;
    const int wv = g.weight("w", {128, 64}), bv = g.weight("b", {64});
    ops::GroupLinear max;
    max.max = true, max.group = 128;
    g.output(ops::group_linear(g, {g.input("big", {128, 128 * 128}), wv, bv}, max, "big"), "big");
    g.output(ops::group_linear(g, {g.input("small", {128, 256}), wv, bv}, {}, "small"), "small");
    max.tile = ops::GroupLinear::Tile::Big16x32;  // forced: the same on every device
    g.output(ops::group_linear(g, {g.input("forced", {128, 128 * 128}), wv, bv}, max, "forced"), "forced");
    GpuExecutor exec(test::gpu(), g, w);
    std::map<std::string, std::pair<uint32_t, uint32_t>> tile;
    std::map<std::string, uint64_t> workgroups;
    for (const auto& r : exec.sequence().dispatch_log()) {
        tile[r.node] = {r.spec.at(1), r.spec.at(2)};
        workgroups[r.node] = uint64_t(r.groups[0]) * r.groups[1] * r.groups[2];
        // Channel blocks along x (spec constant 14), row blocks along y.
        CHECK(r.spec.at(14) == 1u);
        CHECK(r.groups[0] == (64 + r.spec.at(2) - 1) / r.spec.at(2));
        if (r.node != "small") CHECK(r.groups[1] > 1u);  // 128 groups of 128 rows
    }
    INFO(d.name << ", host vector registers " << d.host_vector_registers);
    CHECK(tile.at("forced") == std::make_pair(16u, 32u));
    if (d.type == VK_PHYSICAL_DEVICE_TYPE_CPU) {
        CHECK(tile.at("big") == std::make_pair(8u, 32u));
        CHECK(tile.at("small") == std::make_pair(8u, 16u));
        return;
    }
    // A GPU (an H200 ran this): at most 8 x 16, shrunk until the dispatch offers every
    // compute unit a workgroup or the tile is the smallest (a max keeps its 8 rows).
    const uint64_t want = rt::fill_workgroups(d);
    for (const char* n : {"big", "small"}) {
        INFO(n << ": tile " << tile.at(n).first << " x " << tile.at(n).second << ", " << workgroups.at(n)
                << " workgroups, " << want << " wanted");
        CHECK(tile.at(n).first <= 8u);
        CHECK(tile.at(n).second <= 16u);
        const bool smallest = tile.at(n).second == 4u && tile.at(n).first == (std::string(n) == "big" ? 8u : 4u);
        CHECK((workgroups.at(n) >= want || smallest));
    }
}

namespace {

struct HiddenCase {
    int64_t cf, S, ns, C1, C2;
};

// a first layer computed in registers (hidden) equals the two layers: the cases given.
void hidden_layer_cases(std::initializer_list<HiddenCase> cases, const Sweep& sweep = {}) {
    // The first layer of a set-abstraction scale inside the second (group_linear
    // hidden: from the gathered row, or from that layer per source point, stored
    // point-major) against the same two layers as separate nodes: 0, 3 and 4 feature
    // columns (4 from a wider feature tensor), widths 4 .. 64, balls of 5 .. 128,
    // odd and vec4 output widths, plain and max outputs, both buffer paths (and
    // from the gathered row every weight path and the big-layer tiles). All are
    // checked against the CPU reference.
    std::map<std::string, int> sets_run;  // per variant, which of plain (1) and max (2) ran
    size_t ci = 0;
    for (HiddenCase c : cases) {
        const int64_t N = 300, K0 = c.cf + 3;
        size_t variant = 0;
        WeightStore w;
        w.add("w0", test::random_tensor({K0, c.C1}, 61, -0.5f, 0.5f));
        w.add("b0", test::random_tensor({c.C1}, 62, -0.2f, 0.2f));
        w.add("w1", test::random_tensor({c.C1, c.C2}, 63, -0.3f, 0.3f));
        w.add("b1", test::random_tensor({c.C2}, 64, -0.2f, 0.2f));
        w.add("w_odd", test::random_tensor({K0, 37}, 67, -0.5f, 0.5f));  // point-major stores of 37 channels
        w.add("b_odd", test::random_tensor({37}, 68, -0.2f, 0.2f));
        Graph g;
        const int x = g.input("cloud", {N, 6}), feat = g.input("feat", {N, 10});
        std::vector<int> f = ops::fps(g, x, c.S);
        const int ball = ops::ball_query(g, x, f[1], 0.6, c.ns);
        const int w0 = g.weight("w0", {K0, c.C1}), b0 = g.weight("b0", {c.C1}), w1 = g.weight("w1", {c.C1, c.C2}),
                  b1 = g.weight("b1", {c.C2});
        using In = ops::GroupLinear::Input;
        std::vector<int> gin{x, f[1], ball};
        int64_t fb = 0;
        if (c.cf == 3) gin.push_back(x), fb = 3;  // the normals
        if (c.cf == 4) gin.push_back(feat), fb = 6;
        for (ops::BufferPath path : sweep.paths)
            for (Weights ubo : sweep.weights)
                for (Tile tile : sweep.tiles) {
                    if (path == ops::BufferPath::Storage && ubo != Weights::Shuffle) continue;
                    // 8 x 32 differs from the others only in its spec constants: the path CPU devices take.
                    if (tile == Tile::Big8x32 && ubo != Weights::Shuffle) continue;
                    if (tile != Tile::Auto && !test::big_tiles_apply()) continue;
                    if (!sweep.takes(path, tile)) continue;
                    if (path == ops::BufferPath::Texel) require_weight_path(ubo);
                    const bool big = tile != Tile::Auto;
                    const std::string on = std::string(".") + ops::path_name(path) + "." + weights_name(ubo) +
                                           (tile == Tile::Big16x32 ? ".big" : tile == Tile::Big8x32 ? ".big8" : "");
                    const size_t vi = variant++;
                    for (bool max : {false, true}) {
                        if (!sweep.runs(vi, ci, max)) continue;  // plain and max take turns (Sweep)
                        sets_run[on] |= max ? 2 : 1;
                        ops::GroupLinear first{In::Gather, fb, false, 1, ops::kActRelu, 0.01, path, ubo};
                        std::vector<int> fin = gin;
                        fin.insert(fin.begin() + 3, {w0, b0});
                        const int h = ops::group_linear(g, fin, first);
                        const int two = ops::group_linear(g, {h, w1, b1}, {In::Rows, 0, max, c.ns, ops::kActRelu, 0.01, path, ubo, tile});
                        ops::GroupLinear hid = first;
                        hid.max = max, hid.tile = tile, hid.hidden = ops::GroupLinear::Hidden::Gathered;
                        std::vector<int> hin = gin;
                        hin.insert(hin.begin() + 3, {w0, b0, w1, b1});
                        g.output(two, (max ? "two_max" : "two") + on);
                        g.output(ops::group_linear(g, hin, hid), (max ? "hidden_max" : "hidden") + on);
                        // Layer one per source point (point-major), then the ball rows from it;
                        // the tile and the weight path are the code tested above (their shaders
                        // compile for seconds), so once on each buffer path.
                        if (big || ubo == Weights::Uniform) continue;
                        ops::GroupLinear per{In::Points, fb, false, 1, ops::kActNone, 0.01, path, ubo};
                        per.point_major = true;
                        std::vector<int> pin{x, w0, b0};
                        if (c.cf > 0) pin.push_back(gin[3]);
                        const int u = ops::group_linear(g, pin, per);
                        hid.hidden = ops::GroupLinear::Hidden::PerPoint;
                        g.output(ops::group_linear(g, {u, f[1], ball, w0, w1, b1}, hid), (max ? "perpoint_max" : "perpoint") + on);
                        if (max && sweep.runs(vi, ci, 0)) continue;  // once per variant and case
                        g.output(u, "u_pm" + on);
                        per.point_major = false;
                        g.output(ops::group_linear(g, pin, per), "u_cm" + on);
                        pin[1] = g.weight("w_odd", {K0, 37}), pin[2] = g.weight("b_odd", {37});
                        g.output(ops::group_linear(g, pin, per), "u_cm_odd" + on);
                        per.point_major = true;
                        g.output(ops::group_linear(g, pin, per), "u_pm_odd" + on);
                    }
                }
        INFO("features " << c.cf << ", " << c.S << " balls of " << c.ns << ", widths " << c.C1 << ", " << c.C2);
        const TensorMap out =
            test::run_gpu_and_compare(g, w, {{"cloud", random_cloud(N, 65, 6)}, {"feat", test::random_tensor({N, 10}, 66)}});
        for (const auto& [name, t] : out)
            for (const std::string fused : {"hidden", "perpoint"})
                if (name.rfind(fused, 0) == 0) {
                    const std::string two = "two" + name.substr(fused.size());
                    CHECK(t.shape == out.at(two).shape);
                    test::require_close(t, out.at(two), {}, name + " = " + two);
                }
        for (const auto& [name, pm] : out)  // point-major [P, C1] = channel-major [C1, P] transposed
            if (name.rfind("u_pm", 0) == 0) {
                const HostTensor& cm = out.at("u_cm" + name.substr(4));
                const int64_t C = cm.shape.at(0);
                REQUIRE(pm.shape == Shape{N, C});
                REQUIRE(cm.shape == Shape{C, N});
                int64_t differ = 0;
                for (int64_t p = 0; p < N; ++p)
                    for (int64_t k = 0; k < C; ++k) differ += pm.data[size_t(p * C + k)] != cm.data[size_t(k * N + p)];
                CHECK(differ == 0);
            }
        ++ci;
    }
    require_both_sets(sets_run, cases.size(), sweep);
}

}  // namespace

TEST_CASE("a first layer computed in registers (hidden) equals the two layers", "[op][group_linear][sweep]") {
    // Every path but the 16 x 32 tile (Sweep), each once (Sweep::once_over): a plain or
    // a max second layer on one of two shapes, 4 feature columns from a wider tensor
    // with balls of 128 (around 3 centres; 16 in the long suite, with every set of
    // every tile on every shape) or the normals with an odd output width. No feature
    // columns on shuffled weights and the device's tile (each buffer path's default;
    // plain and max take turns over the two paths).
    hidden_layer_cases({HiddenCase{4, 3, 128, 64, 96}, HiddenCase{3, 9, 32, 64, 37}}, once_each({}, 2));
    hidden_layer_cases({HiddenCase{0, 19, 5, 4, 8}}, Sweep{{Tile::Auto}, {Weights::Shuffle}});
}

TEST_CASE("a first layer computed in registers (hidden) by the subgroup shader equals the two layers",
          "[op][group_linear][subgroup_sweep]") {
    // The sweep above on the variants that depend on the subgroup size (kSubgroupShader),
    // for the README's subgroup-4 run; the third shape's plain and max both on that path.
    hidden_layer_cases({HiddenCase{4, 3, 128, 64, 96}, HiddenCase{3, 9, 32, 64, 37}}, once_each(kSubgroupShader, 2));
    hidden_layer_cases({HiddenCase{0, 19, 5, 4, 8}}, Sweep{{Tile::Auto}, {Weights::Shuffle}, false, {ops::BufferPath::Texel}});
}

// The full-size shapes, one list for both sweeps.
static void hidden_layer_full_size(const Sweep& sweep) {
    hidden_layer_cases({HiddenCase{3, 37, 12, 20, 33}, HiddenCase{0, 19, 5, 4, 8}, HiddenCase{4, 16, 128, 64, 96}, HiddenCase{3, 9, 32, 64, 37}},
                       sweep);
}

TEST_CASE("a first layer computed in registers (hidden) equals the two layers, at full size", "[long][group_linear]") {
    hidden_layer_full_size(kEveryTile);
}

TEST_CASE("a first layer computed in registers (hidden) by the subgroup shader equals the two layers, at full size",
          "[long][group_linear][subgroup_sweep]") {
    hidden_layer_full_size(kSubgroupShaderEveryTile);
}

TEST_CASE("cloud normalisation matches the CPU reference", "[op][cloud_normalize]") {
    for (int64_t N : {1, 2, 1000, 4097}) {
        HostTensor c = test::random_tensor({N, 6}, uint32_t(40 + N), -50.0f, 80.0f);
        if (N == 1) c.data[0] += 1.0f;  // one point: scale 0 -> the CPU reference throws; tested below
        Graph g;
        auto o = ops::cloud_normalize(g, g.input("c", {N, 6}));
        g.output(o[0], "cloud");
        g.output(o[1], "frame");
        INFO("N " << N);
        if (N == 1) {
            REQUIRE_THROWS_WITH(run_cpu(g, WeightStore{}, {{"c", c}}), Catch::Contains("identical"));
            continue;
        }
        // The fp32 mean of coordinates up to 80 carries ~1e-5 absolute error; the
        // normalised coordinates (divided by a scale of ~100) are well within 1e-4.
        TensorMap out = test::run_gpu_and_compare(g, WeightStore{}, {{"c", c}}, {2e-4, 1e-4});
        const HostTensor& y = out.at("cloud");
        double max_norm = 0;
        for (int64_t i = 0; i < N; ++i)
            max_norm = std::max(max_norm, std::hypot(double(y.data[size_t(6 * i)]), double(y.data[size_t(6 * i + 1)]),
                                                     double(y.data[size_t(6 * i + 2)])));
        CHECK(max_norm == Approx(1.0).epsilon(1e-5));
    }
}

TEST_CASE("point ops reject bad inputs with clear errors", "[op][fps][ball_query]") {
    auto infer_error = [](const std::string& op, std::vector<TensorDesc> in, Params p) {
        try {
            find_op(op).infer(in, p);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    CHECK_THAT(infer_error("fps", {TensorDesc{{0, 3}}}, {{"npoint", 1}}), Catch::Contains("empty"));
    CHECK_THAT(infer_error("fps", {TensorDesc{{10, 3}}}, {{"npoint", 11}}), Catch::Contains("cannot sample 11"));
    CHECK_THAT(infer_error("fps", {TensorDesc{{10, 2}}}, {{"npoint", 1}}), Catch::Contains("[N, D >= 3]"));
    CHECK_THAT(infer_error("fps", {TensorDesc{{10, 3}}}, {}), Catch::Contains("npoint"));
    CHECK_THAT(infer_error("ball_query", {TensorDesc{{10, 3}}, TensorDesc{{4, 2}}}, {{"radius", 1}, {"nsample", 2}}),
               Catch::Contains("centres must be [S, 3]"));
    CHECK_THAT(infer_error("ball_query", {TensorDesc{{10, 3}}, TensorDesc{{4, 3}}}, {{"radius", -1}, {"nsample", 2}}),
               Catch::Contains("radius"));
    CHECK_THAT(infer_error("ball_query", {TensorDesc{{10, 3}}, TensorDesc{{4, 3}}}, {{"radius", 1}}),
               Catch::Contains("nsample"));
    CHECK_THAT(infer_error("group_linear", {TensorDesc{{3, 10}}, TensorDesc{{3, 4}}, TensorDesc{{4}}},
                           {{"max", 1}, {"group", 3}}),
               Catch::Contains("do not split"));
    CHECK_THAT(infer_error("group_linear", {TensorDesc{{3, 10}}, TensorDesc{{4, 3}}, TensorDesc{{3}}}, {}),
               Catch::Contains("input-major [3, out]"));
    CHECK_THAT(infer_error("group_linear", {TensorDesc{{3, 10}}, TensorDesc{{3, 4}}, TensorDesc{{4}}}, {{"weights", 3}}),
               Catch::Contains("weights"));
    // hidden = 1: gathered rows [cloud [10, 6], centres, idx], W0^T, b0, W^T, b (, features).
    const TensorDesc cloud{{10, 6}}, centres{{2, 3}}, idx{{2, 4}, ElemType::I32};
    auto hidden = [&](Shape w0, Shape b0, int64_t feat_begin) {
        return infer_error("group_linear", {cloud, centres, idx, TensorDesc{w0}, TensorDesc{b0}, TensorDesc{{8, 5}},
                                            TensorDesc{{5}}, TensorDesc{{10, 9}}},
                           {{"in", 1}, {"hidden", 1}, {"feat_begin", double(feat_begin)}});
    };
    CHECK(hidden({6, 8}, {8}, 6) == "no error");  // 3 features + xyz
    CHECK_THAT(hidden({6, 6}, {6}, 6), Catch::Contains("hidden width 6 is not a multiple of 4"));
    CHECK_THAT(hidden({5, 8}, {8}, 6), Catch::Contains("hidden weight [5, 8] must be input-major [6, width]"));
    CHECK_THAT(hidden({12, 8}, {8}, 0), Catch::Contains("at most 4 feature columns, got 9"));
    CHECK_THAT(hidden({6, 8}, {6}, 6), Catch::Contains("hidden bias [6] does not match [6, 8]"));
    CHECK_THAT(infer_error("group_linear", {TensorDesc{{3, 10}}, TensorDesc{{3, 4}}, TensorDesc{{4}}}, {{"hidden", 1}}),
               Catch::Contains("hidden = 1 needs gathered rows (in = 1)"));
    // hidden = 2: [U [10, K], centres, idx, W0^T [K0 >= 3, K], W^T [K, 5], b [5]].
    auto per_point = [&](Shape u, Shape w0) {
        return infer_error("group_linear", {TensorDesc{u}, centres, idx, TensorDesc{w0}, TensorDesc{{u[1], 5}}, TensorDesc{{5}}},
                           {{"in", 1}, {"hidden", 2}});
    };
    CHECK(per_point({10, 8}, {9, 8}) == "no error");
    CHECK_THAT(per_point({10, 6}, {9, 6}), Catch::Contains("U [10, 6]: its width is not a multiple of 4"));
    CHECK_THAT(per_point({10, 8}, {2, 8}), Catch::Contains("hidden weight [2, 8] must be input-major [K0 >= 3, 8]"));
    CHECK_THAT(per_point({10, 8}, {9, 4}), Catch::Contains("hidden weight [9, 4] must be input-major [K0 >= 3, 8]"));
    CHECK_THAT(infer_error("group_linear", {TensorDesc{{3, 12}}, TensorDesc{{3, 4}}, TensorDesc{{4}}},
                           {{"max", 1}, {"group", 3}, {"point_major", 1}}),
               Catch::Contains("point_major = 1 is for plain outputs"));
    // NaN / inf coordinates: the CPU references throw (the GPU path relies on the host check).
    for (float bad : {std::nanf(""), INFINITY}) {
        HostTensor c = random_cloud(50, 7);
        c.data[31] = bad;
        Graph g;
        std::vector<int> f = ops::fps(g, g.input("c", {50, 3}), 5);
        g.output(f[0], "i");
        REQUIRE_THROWS_WITH(run_cpu(g, WeightStore{}, {{"c", c}}), Catch::Contains("point 10 has a NaN or infinite"));
    }
    test::require_no_validation_messages();
}

TEST_CASE("layer one per source point plus sa_gather equals the gathered layer, both buffer paths",
          "[op][sa_gather][group_linear]") {
    // group_linear (Points) gives U = W [features, xyz] + b per source point;
    // sa_gather takes U[q] - W_xyz c_s per ball row. Both match their CPU
    // references, and together the direct gathered layer (group_linear, Gather):
    // the same sums, grouped differently, so within the default tolerance.
    // NS = 7: 259 rows, one per invocation; NS = 8: 296 rows, 4 per invocation (vec4 stores).
    const int64_t P = 301, S = 37, N = 10;
    HostTensor cloud = test::random_tensor({P, 6}, 41), centres = test::random_tensor({S, 3}, 42), feat = test::random_tensor({P, 13}, 43);
    for (int64_t NS : {7, 8})
    for (bool own_features : {false, true}) {  // the cloud's normals, or a feature tensor from column 2
        std::vector<int32_t> idx(size_t(S * NS));
        uint32_t st = 9;
        for (auto& v : idx) v = int32_t((st = st * 1664525u + 1013904223u) >> 8) % int32_t(P);
        const int64_t fb = own_features ? 2 : 3, CF = own_features ? 11 : 3, K = CF + 3;
        for (ops::BufferPath path : ops::kBufferPaths) {
            INFO("NS " << NS << ", features " << (own_features ? "separate" : "the cloud's normals") << ", path " << ops::path_name(path));
            Graph g;
            TensorMap in{{"cloud", cloud}, {"centres", centres}, {"idx", HostTensor::from_ints({S, NS}, idx)},
                         {"w", test::random_tensor({K, N}, 44, -0.5f, 0.5f)}, {"b", test::random_tensor({N}, 45)}};
            const int x = g.input("cloud", cloud.shape), c = g.input("centres", centres.shape);
            const int ix = g.input("idx", {S, NS}, ElemType::I32), w = g.input("w", {K, N}), b = g.input("b", {N});
            int f = x;
            if (own_features) {
                f = g.input("feat", feat.shape);
                in["feat"] = feat;
            }
            ops::GroupLinear per_point;
            per_point.input = ops::GroupLinear::Input::Points;
            per_point.feat_begin = fb;
            per_point.path = path;
            const int u = ops::group_linear(g, {x, w, b, f}, per_point);
            g.output(u, "u");
            g.output(ops::sa_gather(g, u, c, ix, w, ops::kActRelu, "", path), "factored");
            ops::GroupLinear gather;
            gather.input = ops::GroupLinear::Input::Gather;
            gather.feat_begin = fb;
            gather.act = ops::kActRelu;
            gather.path = path;
            g.output(ops::group_linear(g, {x, c, ix, w, b, f}, gather), "direct");
            TensorMap out = test::run_gpu_and_compare(g, WeightStore{}, in);
            REQUIRE(out.at("factored").shape == Shape{N, S * NS});
            test::require_close(out.at("factored"), out.at("direct"), test::Tolerance{}, "factored vs direct layer one");
        }
    }
}

TEST_CASE("FPS and ball query refuse, on a CPU driver, clouds whose scan would outrun its loop limit", "[op][fps][ball_query]") {
    // Lavapipe ends a shader's loops after 65,535 iterations per invocation
    // (engine/ops/common.h); these ops have no split, so they refuse by name.
    const rt::DeviceInfo& d = test::gpu().info();
    if (d.type != VK_PHYSICAL_DEVICE_TYPE_CPU) return;  // a GPU runs them at any size (the sizes above)
    Graph g;
    const int big = g.input("pts", {200000, 3});
    g.output(ops::fps(g, big, 512)[0], "idx");
    REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g, WeightStore{}), Catch::Contains("FPS of 512 from 200000 points") &&
                                                                         Catch::Contains("CPU driver"));
    Graph g2;
    const int pts = g2.input("pts", {70000, 3}), c = g2.input("c", {4, 3});
    g2.output(ops::ball_query(g2, pts, c, 0.1, 8), "idx");
    REQUIRE_THROWS_WITH(GpuExecutor(test::gpu(), g2, WeightStore{}), Catch::Contains("ball query over 70000 points"));
}
