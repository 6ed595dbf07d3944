// Self-test cases: fps, ball_query, point_group, group_max, group_linear
// (gather, plain, group-all and per-point inputs; a hidden first layer from the
// gathered rows or per point; fused max; ball padding skipped; texel and storage-buffer paths), sa_gather, cloud_normalize (the shapes of tests/test_point_ops.cpp) and
// normal_estimate (a sphere sample, as tests/test_normals.cpp).
#include <algorithm>
#include <cmath>

#include "engine/check/op_selftest.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "engine/ops/point_common.h"
#include "engine/ops/point_grid.h"

namespace vtloc::check {

namespace {

OpCase fps_case(int64_t n, int64_t d, int64_t npoint, double radius, int64_t nsample, bool no_registers,
                const std::string& why, bool tree = false) {
    OpCase c("fps", why + ": " + std::to_string(n) + " points [N, " + std::to_string(d) + "] -> " +
                        std::to_string(npoint));
    int x = c.input("cloud", random_tensor({n, d}, uint32_t(n)));
    std::vector<int> f = ops::fps(c.g, x, npoint, "", no_registers, tree);
    c.output(f[0], "fps");
    c.output(f[1], "centres");
    if (nsample > 0) c.output(ops::ball_query(c.g, x, f[1], radius, nsample, "", tree), "ball");
    return c;
}

// A PointNet++ stage: grouping, fused layers, neighbour max (ReLU).
OpCase stage_case(const std::string& op, const std::string& why, ops::BufferPath path) {
    const int64_t N = 300, S = 37, ns = 12, C1 = 20, C2 = 33, C3 = 24;
    const ops::Act relu = ops::kActRelu;
    OpCase c(op, why);
    int x = c.input("cloud", random_tensor({N, 6}, 21));
    std::vector<int> f = ops::fps(c.g, x, S);
    int ball = ops::ball_query(c.g, x, f[1], 0.6, ns);
    HostTensor w1 = random_tensor({C1, 6}, 11, -0.5f, 0.5f), w2 = random_tensor({C2, C1}, 13, -0.3f, 0.3f);
    HostTensor w3 = random_tensor({C3, 3 + C1}, 15, -0.3f, 0.3f);
    int b1 = c.weight("b1", random_tensor({C1}, 12, -0.2f, 0.2f)), b2 = c.weight("b2", random_tensor({C2}, 14, -0.2f, 0.2f));
    int b3 = c.weight("b3", random_tensor({C3}, 16, -0.2f, 0.2f));
    int w1t = c.weight("w1t", ops::point_weight_kn(w1)), w2t = c.weight("w2t", ops::point_weight_kn(w2));
    int w3t = c.weight("w3t", ops::point_weight_kn(w3));
    int w1v = c.weight("w1", w1), w2v = c.weight("w2", w2);
    std::vector<int> fin{x, f[1], ball, w1t, b1, x};
    using In = ops::GroupLinear::Input;
    // gather (first layer), plain rows with the fused max, gather + max, group-all + max
    const ops::GroupLinear gather{In::Gather, 3, false, 1, relu, 0.01, path};
    const ops::GroupLinear rows_max{In::Rows, 0, true, ns, relu, 0.01, path};
    const ops::GroupLinear gather_max{In::Gather, 3, true, 1, relu, 0.01, path};
    const ops::GroupLinear all_max{In::GroupAll, 0, true, S, ops::kActNone, 0.01, path};
    if (op == "point_group") {
        int grouped = ops::point_group(c.g, {x, f[1], ball, x}, 3);
        c.output(grouped, "grouped");
        int h = ops::linear(c.g, grouped, w1v, b1, relu);
        c.output(ops::linear(c.g, h, w2v, b2, relu), "y");
    } else if (op == "group_max") {
        int fh = ops::group_linear(c.g, fin, gather);
        c.output(ops::group_max(c.g, fh, ns, true), "max_cm");
        int grouped = ops::point_group(c.g, {x, f[1], ball, x}, 3);
        int h = ops::linear(c.g, grouped, w1v, b1, relu);
        c.output(ops::group_max(c.g, h, ns, false), "max_pm");
    } else {
        int fh = ops::group_linear(c.g, fin, gather);
        c.output(fh, "first");
        c.output(ops::group_linear(c.g, {fh, w2t, b2}, rows_max), "fused");
        // the first layer computed inside the second (hidden), plain and with the max
        ops::GroupLinear hidden = gather;
        hidden.hidden = ops::GroupLinear::Hidden::Gathered;
        const std::vector<int> hin{x, f[1], ball, w1t, b1, w2t, b2, x};
        c.output(ops::group_linear(c.g, hin, hidden), "hidden");
        hidden.max = true;
        c.output(ops::group_linear(c.g, hin, hidden), "hidden_max");
        int one = ops::group_linear(c.g, fin, gather_max);
        c.output(ops::group_linear(c.g, {f[1], w3t, b3, one}, all_max), "all");
        // ball padding skipped (pad), on balls of 16 that are mostly padding (whole
        // blocks skipped): the max after a skipping hidden layer, and a gathered max
        const int64_t pns = 16;
        const int pball = ops::ball_query(c.g, x, f[1], 0.3, pns);
        ops::GroupLinear hidden_pad = gather;
        hidden_pad.hidden = ops::GroupLinear::Hidden::Gathered;
        hidden_pad.skip_padding = true;
        ops::GroupLinear rows_pad{In::Rows, 0, true, pns, relu, 0.01, path};
        rows_pad.skip_padding = true;
        const int w4t = c.weight("w4t", ops::point_weight_kn(random_tensor({C3, C2}, 17, -0.3f, 0.3f)));
        const int hp = ops::group_linear(c.g, {x, f[1], pball, w1t, b1, w2t, b2, x}, hidden_pad);
        c.output(ops::group_linear(c.g, {hp, w4t, b3, pball}, rows_pad), "pad_max");
        ops::GroupLinear gather_max_pad = gather_max;
        gather_max_pad.skip_padding = true;
        c.output(ops::group_linear(c.g, {x, f[1], pball, w1t, b1, x}, gather_max_pad), "gather_max_pad");
        // the same pair passing its rows point-major (the point encoder's default)
        hidden_pad.point_major = true;
        rows_pad.x_point_major = true;
        const int hpm = ops::group_linear(c.g, {x, f[1], pball, w1t, b1, w2t, b2, x}, hidden_pad);
        c.output(ops::group_linear(c.g, {hpm, w4t, b3, pball}, rows_pad), "pad_max_point_major");
    }
    return c;
}

// Layer one per source point (group_linear, Points) and sa_gather, both buffer paths.
void add_sa_gather_cases(std::vector<OpCase>& v) {
    const int64_t P = 301, S = 37, NS = 7, N = 10, K = 6;
    std::vector<int32_t> idx(size_t(S * NS));
    uint32_t st = 9;
    for (auto& x : idx) x = int32_t((st = st * 1664525u + 1013904223u) >> 8) % int32_t(P);
    for (ops::BufferPath path : ops::kBufferPaths) {
        OpCase c("sa_gather", std::string("layer one per point of 301, 37 balls of 7, ") + ops::path_name(path));
        const int x = c.input("cloud", random_tensor({P, 6}, 41)), w = c.input("w", random_tensor({K, N}, 44, -0.5f, 0.5f));
        ops::GroupLinear per_point;
        per_point.input = ops::GroupLinear::Input::Points;
        per_point.feat_begin = 3;
        per_point.path = path;
        const int u = ops::group_linear(c.g, {x, w, c.input("b", random_tensor({N}, 45)), x}, per_point);
        c.output(u, "u");
        const int centres = c.input("centres", random_tensor({S, 3}, 42));
        const int ball = c.input("idx", HostTensor::from_ints({S, NS}, idx));
        c.output(ops::sa_gather(c.g, u, centres, ball, w, ops::kActRelu, "", path), "y");
        // Such rows unstored: U point-major (12 channels: a multiple of 4), then a
        // layer whose input they are (hidden), with the max.
        per_point.point_major = true;
        const int w12 = c.input("w12", random_tensor({K, 12}, 48, -0.5f, 0.5f));
        const int upm = ops::group_linear(c.g, {x, w12, c.input("b12", random_tensor({12}, 49)), x}, per_point);
        c.output(upm, "u_point_major");
        ops::GroupLinear next{ops::GroupLinear::Input::Gather, 0, true, 1, ops::kActRelu, 0.01, path};
        next.hidden = ops::GroupLinear::Hidden::PerPoint;
        c.output(ops::group_linear(c.g, {upm, centres, ball, w12, c.weight("w2", random_tensor({12, 6}, 46, -0.5f, 0.5f)),
                                         c.weight("b2", random_tensor({6}, 47))}, next),
                 "next_max");
        v.push_back(std::move(c));
    }
}

// group_linear with ball padding skipped on uneven_balls (the shuffle shader pools a
// subgroup's chunks): a gathering layer (layer one in registers) and the max after
// it, both row layouts, and a gathered max. row_blocks: the gathering layer in row
// blocks, as GPUs run it (each way a case of its own: in one graph, one layer could
// be handed the other's memory, values and all).
OpCase uneven_balls_case(bool row_blocks) {
    const int64_t P = 300, S = 40, NS = 64;
    OpCase c("group_linear", std::string("ball padding skipped, 40 balls of 1 to 64 rows; ") +
                                 (row_blocks ? "gathering layer in row blocks" : "chunks pooled"));
    const int x = c.input("cloud", random_tensor({P, 6}, 61)), centres = c.input("centres", random_tensor({S, 3}, 62));
    const int ball = c.input("ball", uneven_balls(S, NS, P));
    const int w0 = c.weight("w0", random_tensor({6, 16}, 63, -0.5f, 0.5f)), b0 = c.weight("b0", random_tensor({16}, 64, -0.2f, 0.2f));
    const int w1 = c.weight("w1", random_tensor({16, 24}, 65, -0.3f, 0.3f)), b1 = c.weight("b1", random_tensor({24}, 66, -0.2f, 0.2f));
    const int w2 = c.weight("w2", random_tensor({24, 40}, 67, -0.3f, 0.3f)), b2 = c.weight("b2", random_tensor({40}, 68, -0.2f, 0.2f));
    using In = ops::GroupLinear::Input;
    for (bool pm : {false, true}) {
        ops::GroupLinear first{In::Gather, 3, false, 1, ops::kActRelu};
        first.hidden = ops::GroupLinear::Hidden::Gathered;
        first.skip_padding = true, first.point_major = pm, first.row_blocks = row_blocks;
        const int h = ops::group_linear(c.g, {x, centres, ball, w0, b0, w1, b1, x}, first);
        ops::GroupLinear last{In::Rows, 0, true, NS, ops::kActRelu};
        last.skip_padding = true, last.x_point_major = pm;
        c.output(ops::group_linear(c.g, {h, w2, b2, ball}, last), pm ? "max_point_major" : "max");
    }
    if (!row_blocks) {
        ops::GroupLinear one{In::Gather, 3, true, 1, ops::kActRelu};
        one.skip_padding = true;
        c.output(ops::group_linear(c.g, {x, centres, ball, w0, b0, x}, one), "gathered_max");
    }
    return c;
}

// group_linear on a plain input: the max over groups and a plain leaky layer.
void wide_cases(std::vector<OpCase>& v, bool cpu_device) {
    struct Wide { int64_t M, K, Nout, group; };
    for (Wide k : {Wide{20 * 128, 131, 96, 128}, Wide{1001, 37, 37, 13}}) {
        OpCase c("group_linear", "plain input [" + std::to_string(k.K) + ", " + std::to_string(k.M) + "] -> " +
                                     std::to_string(k.Nout) + ", max over groups of " + std::to_string(k.group));
        int x = c.input("x", random_tensor({k.K, k.M}, 33));
        int wv = c.weight("w", random_tensor({k.K, k.Nout}, 31, -0.15f, 0.15f));
        int bv = c.weight("b", random_tensor({k.Nout}, 32, -0.1f, 0.1f));
        ops::GroupLinear max;
        max.max = true;
        max.group = k.group;
        c.output(ops::group_linear(c.g, {x, wv, bv}, max), "max");
        if (cpu_device) {  // the tiles that CPU devices use on big layers
            max.tile = ops::GroupLinear::Tile::Big16x32;
            c.output(ops::group_linear(c.g, {x, wv, bv}, max), "max_big_tile");
            max.tile = ops::GroupLinear::Tile::Big8x32;
            c.output(ops::group_linear(c.g, {x, wv, bv}, max), "max_big_tile_8x32");
        }
        ops::GroupLinear plain;
        plain.act = ops::kActLeaky;
        plain.slope = 0.1;
        c.output(ops::group_linear(c.g, {x, wv, bv}, plain), "plain");
        plain.weights = ops::GroupLinear::Weights::Uniform;  // as on devices without subgroup shuffles
        c.output(ops::group_linear(c.g, {x, wv, bv}, plain), "plain_uniform_weights");
        plain.weights = ops::GroupLinear::Weights::Storage;  // as where they fit neither
        c.output(ops::group_linear(c.g, {x, wv, bv}, plain), "plain_storage_weights");
        v.push_back(std::move(c));
    }
}

void cloud_normalize_cases(std::vector<OpCase>& v) {
    for (int64_t n : {2, 4097}) {
        OpCase c("cloud_normalize", std::to_string(n) + " points, coordinates in -50..80");
        auto o = ops::cloud_normalize(c.g, c.input("c", random_tensor({n, 6}, uint32_t(40 + n), -50.0f, 80.0f)));
        c.output(o[0], "cloud");
        c.output(o[1], "frame");
        c.tol = {2e-4, 1e-4};  // the fp32 mean of coordinates up to 80 (as tests/test_point_ops.cpp)
        v.push_back(std::move(c));
    }
}

void normal_estimate_cases(std::vector<OpCase>& v) {
    for (int k : {5, 16}) {
        OpCase c("normal_estimate", "sphere of 777 points, k = " + std::to_string(k));
        HostTensor xyz = random_tensor({777, 3}, uint32_t(50 + k));
        for (int64_t i = 0; i < 777; ++i) {  // onto a sphere of radius 20: a smooth surface
            float* p = &xyz.data[size_t(i * 3)];
            const float l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            for (int a = 0; a < 3; ++a) p[a] = 20.0f * p[a] / l;
        }
        const ops::PointGrid grid = ops::build_point_grid(xyz, k);
        const int x = c.input("points", xyz), o = c.input("order", grid.order), s0 = c.input("cell_start", grid.cell_start);
        c.output(ops::normal_estimate(c.g, x, o, s0, grid, k, 1, {0, 0, 0}), "normals");
        c.tol = {2e-3, 0};  // fp32 PCA in the shader, double in the reference (tests/test_normals.cpp)
        v.push_back(std::move(c));
    }
}

}  // namespace

HostTensor uneven_balls(int64_t S, int64_t NS, int64_t P) {
    std::vector<int32_t> idx(size_t(S * NS));
    for (int64_t s = 0; s < S; ++s) {
        const int64_t used = s >= 32 ? std::min<int64_t>(20, NS)
                             : s % 8 == 3 ? NS
                             : s % 8 == 5 ? std::min<int64_t>(40, NS)
                                          : std::min<int64_t>(1 + (s * 5) % 7, NS);
        for (int64_t j = 0; j < NS; ++j)  // j * 7 % P: distinct while P has no factor 7 (P = 300)
            idx[size_t(s * NS + j)] = int32_t(j < used ? (s * 37 + j * 7) % P : (s * 37) % P);
    }
    if (S > 11 && NS > 6) idx[size_t(11 * NS + 5)] = idx[size_t(11 * NS)];  // real rows after it
    return HostTensor::from_ints({S, NS}, idx);
}

std::vector<OpCase> point_cases(const rt::DeviceInfo& d) {
    std::vector<OpCase> v;
    v.push_back(fps_case(1000, 3, 1000, 0, 0, false, "npoint = N, not a power of two"));
    v.push_back(fps_case(200, 3, 64, 0, 0, false, "one subgroup on CPU devices"));  // no barrier there
    v.push_back(fps_case(5000, 3, 512, 0, 0, false, "registers path"));
    v.push_back(fps_case(5000, 3, 512, 0, 0, false, "tree reduction", true));  // the shared-memory shaders
    v.push_back(fps_case(2000, 3, 300, 0, 0, true, "workspace path"));
    for (OpCase c : {fps_case(333, 6, 100, 0.2, 7, false, ""), fps_case(5000, 3, 512, 0.1, 32, false, ""),
                     fps_case(5000, 3, 512, 0.1, 32, false, "tiles", true)}) {
        c.op = "ball_query";
        c.variant = c.variant.rfind(": ", 0) == 0 ? "after fps: " + c.variant.substr(2) : "after fps, " + c.variant;
        v.push_back(std::move(c));
    }

    v.push_back(stage_case("point_group", "gather 37 groups of 12 from 300 points [N, 6], then two layers",
                           ops::BufferPath::Texel));
    v.push_back(stage_case("group_max", "channel-major and point-major, groups of 12", ops::BufferPath::Texel));
    for (ops::BufferPath path : ops::kBufferPaths)
        v.push_back(stage_case("group_linear",
                               std::string("gather, hidden first layer, fused max, group-all; ") + ops::path_name(path) + " path", path));
    v.push_back(uneven_balls_case(false));
    v.push_back(uneven_balls_case(true));
    wide_cases(v, d.type == VK_PHYSICAL_DEVICE_TYPE_CPU);
    add_sa_gather_cases(v);
    cloud_normalize_cases(v);
    normal_estimate_cases(v);
    return v;
}

}  // namespace vtloc::check
