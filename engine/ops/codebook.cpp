// Render-and-compare (SPEC 9, docs/render_compare.md), its two GPU steps:
// codebook_render: samples [S, 9] (point, normal, t1), points [D, 6] (point, outward
//   normal; binned by a coarse grid, bin by bin), bins [nx*ny*nz, 2] (first point, count; I32)
//   -> heights [S, G*G]: each sample's height map (params G, cell, splat, cap, facing,
//   origin_x/y/z, coarse, nx, ny, nz, max_bin: the largest bin's count, which bounds a
//   workgroup's loop; a sample reads the 27 bins around its own).
// codebook_window_min: quads [S, 4 (G+1)^2] (each map's bilinear quads, book::make_quads),
//   spins -> [S * NS] (params rows, cols, cell, win, cap): each
//   hypothesis' shallowest depth under the window, the depth its press counts from (it
//   depends on the map, the spin and the window's size only: computed once per size).
// codebook_score: quads [S, 4 (G+1)^2], spins [NS, 2] (cos, sin), measured [R, C] (mm), the
//   window minima [S * NS], the measured press [1] (mm) -> log term [S * NS] (params cell,
//   win, cap, weight, quadratic): each hypothesis' height map seen at its spin, pressed as
//   deep as the measured map, against the measured map (the error less its best plane, or
//   plane and quadratic: tilt, offset and the reader's bowl are nuisances).
// CPU references: engine/ops/codebook_math.h. -> shaders/codebook_render.comp (a
// workgroup per sample, atomic minimum over its cells), shaders/codebook_window_min.comp,
// shaders/codebook_score.comp (one pass over the window per hypothesis).
#include <cmath>

#include "base/error.h"
#include "engine/ops/codebook_math.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

double positive(const Params& p, const char* k) {
    const double v = p.get(k, -1);
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string(k) + " must be a positive number");
    return v;
}

int32_t count_param(const Params& p, const char* k, double hi) {
    const double v = p.get(k, -1);
    if (!(v >= 1 && v <= hi) || v != std::floor(v))
        throw Error(std::string(k) + " must be an integer in [1, " + std::to_string(int64_t(hi)) + "]");
    return int32_t(v);
}

book::RenderParams render_params(const Params& p) {
    book::RenderParams r{};
    r.G = count_param(p, "G", 1024);
    r.cell = float(positive(p, "cell"));
    r.splat = float(positive(p, "splat"));
    r.cap = float(positive(p, "cap"));
    r.facing = float(p.get("facing", 0));
    r.origin = {float(p.get("origin_x", 0)), float(p.get("origin_y", 0)), float(p.get("origin_z", 0))};
    r.coarse = float(positive(p, "coarse"));
    r.inv_cell = float(1.0 / double(r.cell)), r.inv_coarse = float(1.0 / double(r.coarse));
    r.nx = count_param(p, "nx", 1 << 20), r.ny = count_param(p, "ny", 1 << 20), r.nz = count_param(p, "nz", 1 << 20);
    if (r.splat / r.cell > 8) throw Error("codebook_render: splat must be at most 8 cells");
    return r;
}

std::vector<TensorDesc> render_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 3, 3);
    const book::RenderParams r = render_params(p);
    if (in[0].type != ElemType::F32 || in[1].type != ElemType::F32 || in[2].type != ElemType::I32)
        throw Error("codebook_render takes f32 samples, f32 points and i32 bins");
    const Shape &s = in[0].shape, &pt = in[1].shape, &b = in[2].shape;
    if (s.size() != 2 || s[1] != 9 || s[0] < 1) throw Error("codebook_render: samples must be [S > 0, 9], got " + shape_str(s));
    if (pt.size() != 2 || pt[1] != 6 || pt[0] < 1) throw Error("codebook_render: points must be [D > 0, 6], got " + shape_str(pt));
    const Shape want{int64_t(r.nx) * r.ny * r.nz, 2};
    if (b != want) throw Error("codebook_render: bins must be " + shape_str(want) + ", got " + shape_str(b));
    to_u32(s[0] * int64_t(r.G) * r.G, "codebook size");
    to_u32(pt[0] * 6, "point array size");
    return {TensorDesc{{s[0], int64_t(r.G) * r.G}}};
}

// Calls f(first, count) for each of the 27 bins around sample point p.
template <class F>
void for_bins(const book::RenderParams& r, const float* p, const int32_t* bins, F f) {
    const int32_t cx = book::coarse_index(p[0], r.origin.x, r.inv_coarse, r.nx), cy = book::coarse_index(p[1], r.origin.y, r.inv_coarse, r.ny),
                  cz = book::coarse_index(p[2], r.origin.z, r.inv_coarse, r.nz);
    for (int32_t z = std::max(0, cz - 1); z <= std::min(r.nz - 1, cz + 1); ++z)
        for (int32_t y = std::max(0, cy - 1); y <= std::min(r.ny - 1, cy + 1); ++y)
            for (int32_t x = std::max(0, cx - 1); x <= std::min(r.nx - 1, cx + 1); ++x) {
                const int64_t bin = (int64_t(z) * r.ny + y) * r.nx + x;
                f(bins[2 * bin], bins[2 * bin + 1]);
            }
}

void render_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const book::RenderParams r = render_params(p);
    const int64_t S = in[0]->shape[0], GG = int64_t(r.G) * r.G;
    const std::vector<int32_t> bins = in[2]->ints();
    const int32_t most = count_param(p, "max_bin", 1 << 30);
    for (size_t b = 1; b < bins.size(); b += 2)
        if (bins[b] < 0 || bins[b] > most || bins[b - 1] < 0 || int64_t(bins[b - 1]) + bins[b] > in[1]->shape[0])
            throw Error("codebook_render: bin " + std::to_string(b / 2) + " (first " + std::to_string(bins[b - 1]) + ", count " +
                        std::to_string(bins[b]) + ") lies outside the points or above max_bin " + std::to_string(most));
    std::vector<uint32_t> cells(static_cast<size_t>(GG));
    for (int64_t s = 0; s < S; ++s) {
        const float* smp = &in[0]->data[size_t(9 * s)];
        std::fill(cells.begin(), cells.end(), book::ordered(r.cap));
        for_bins(r, smp, bins.data(), [&](int32_t first, int32_t count) {
            for (int32_t k = first; k < first + count; ++k) book::splat_point(r, smp, &in[1]->data[size_t(6 * k)], cells.data());
        });
        for (int64_t c = 0; c < GG; ++c) out[0]->data[size_t(s * GG + c)] = book::unordered(cells[size_t(c)]);
    }
}

void render_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const book::RenderParams r = render_params(a.params);
    struct {
        int32_t S, G;
        float inv_cell, splat, cap, facing, ox, oy, oz, inv_coarse;
        int32_t nx, ny, nz;
    } push{int32_t(a.in[0].shape[0]), r.G, r.inv_cell, r.splat, r.cap, r.facing, r.origin.x, r.origin.y, r.origin.z, r.inv_coarse, r.nx, r.ny, r.nz};
    const uint32_t local = elementwise_local_size(d);
    // A workgroup per sample; its invocations stride over the bins' points. The
    // densest 27 bins bound one invocation's loop (a wide workgroup: more headroom
    // under lavapipe's loop limiter for dense objects).
    const int64_t most = count_param(a.params, "max_bin", 1 << 30);
    const int64_t per_splat = int64_t(std::pow(2.0 * r.splat / r.cell + 2, 2));
    check_loop_budget(d, uint64_t(27 * ((most + local - 1) / local + 1) * (per_splat + 1)) + uint64_t(r.G) * r.G * 2 / local + 4,
                      "codebook_render");
    uint32_t groups = uint32_t(std::min<int64_t>(push.S, d.max_workgroup_count[0]));
    a.seq.dispatch(pipeline(a.ctx, "codebook_render", 4, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read}, {a.in[2].view, rt::Access::Read},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), groups);
}

book::ScoreParams score_params(const Params& p, int64_t G, int64_t R, int64_t C) {
    book::ScoreParams s{};
    s.G = int32_t(G), s.R = int32_t(R), s.C = int32_t(C);
    s.inv_cell = float(1.0 / positive(p, "cell"));
    s.win = float(positive(p, "win"));
    s.cap = float(positive(p, "cap"));
    s.weight = float(p.get("weight", 1));
    if (!std::isfinite(s.weight) || s.weight < 0) throw Error("codebook_score: weight must be >= 0");
    return s;
}

// quads [S, 4 (G+1)^2] (book::make_quads of each map) and spins [NS, 2]: returns G.
int64_t quads_side(const Shape& b) { return b.size() == 2 && b[1] % 4 == 0 ? int64_t(std::llround(std::sqrt(double(b[1] / 4)))) : 0; }

int64_t check_book(const char* op, const Shape& b, const Shape& sp) {
    if (b.size() != 2 || b[0] < 1) throw Error(std::string(op) + ": quads must be [S > 0, 4 (G+1)^2], got " + shape_str(b));
    const int64_t Q = quads_side(b);
    if (Q < 2 || 4 * Q * Q != b[1])
        throw Error(std::string(op) + ": a map's quads must be 4 (G+1)^2 values for G >= 1, got " + std::to_string(b[1]));
    if (sp.size() != 2 || sp[1] != 2 || sp[0] < 1) throw Error(std::string(op) + ": spins must be [NS > 0, 2], got " + shape_str(sp));
    to_u32(b[0] * b[1], "codebook size");
    to_u32(b[0] * sp[0], "hypothesis count");
    return Q - 1;
}

void check_window(const char* op, int64_t R, int64_t C) {
    if (R < 1 || C < 1 || R * C > book::kMaxWindowCells)
        throw Error(std::string(op) + ": a window of 1 to " + std::to_string(book::kMaxWindowCells) + " cells, got " + std::to_string(R) +
                    " x " + std::to_string(C));
}

struct Book {
    int64_t S, stride, NS;  // stride: floats per sample, 4 (G+1)^2
    book::ScoreParams s;
};

Book book_of(const Shape& quads, const Shape& spins, const Params& p, int64_t R, int64_t C) {
    return {quads[0], quads[1], spins[0], score_params(p, quads_side(quads) - 1, R, C)};
}

// Push constants both shaders start with (shaders/codebook_window.glsl reads G..cap).
struct WindowPush {
    int32_t H, NS, G, R, C;
    float inv_cell, win, cap;
};

std::vector<TensorDesc> window_min_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 2, 2);
    expect_f32(in);
    const int64_t G = check_book("codebook_window_min", in[0].shape, in[1].shape);
    const int64_t R = count_param(p, "rows", book::kMaxWindowCells), C = count_param(p, "cols", book::kMaxWindowCells);
    check_window("codebook_window_min", R, C);
    score_params(p, G, R, C);
    return {TensorDesc{{in[0].shape[0] * in[1].shape[0]}}};
}

void window_min_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const Book b = book_of(in[0]->shape, in[1]->shape, p, count_param(p, "rows", book::kMaxWindowCells), count_param(p, "cols", book::kMaxWindowCells));
    for (int64_t i = 0; i < b.S; ++i)
        for (int64_t j = 0; j < b.NS; ++j)
            out[0]->data[size_t(i * b.NS + j)] =
                book::window_min(b.s, &in[0]->data[size_t(i * b.stride)], in[1]->data[size_t(2 * j)], in[1]->data[size_t(2 * j + 1)]);
}

void window_min_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const Book b = book_of(a.in[0].shape, a.in[1].shape, a.params, count_param(a.params, "rows", book::kMaxWindowCells),
                           count_param(a.params, "cols", book::kMaxWindowCells));
    const WindowPush push{int32_t(b.S * b.NS), int32_t(b.NS), b.s.G, b.s.R, b.s.C, b.s.inv_cell, b.s.win, b.s.cap};
    const uint32_t local = elementwise_local_size(d), groups = grid_groups(uint64_t(push.H), local, d);
    const uint64_t strides = (uint64_t(push.H) + uint64_t(groups) * local - 1) / (uint64_t(groups) * local);
    check_loop_budget(d, strides * (uint64_t(b.s.R) * uint64_t(b.s.C) + uint64_t(b.s.R) + 1), "codebook_window_min");
    a.seq.dispatch(pipeline(a.ctx, "codebook_window_min", 3, sizeof(push), {local}),
                   {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}}, &push,
                   sizeof(push), groups);
}

bool quadratic_of(const Params& p) {
    const double q = p.get("quadratic", 0);
    if (q != 0 && q != 1) throw Error("codebook_score: quadratic must be 0 (the plane) or 1 (the plane and r^2, c^2, r c)");
    return q == 1;
}

std::vector<TensorDesc> score_infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 5, 5);
    expect_f32(in);
    const int64_t G = check_book("codebook_score", in[0].shape, in[1].shape);
    const Shape& m = in[2].shape;
    if (m.size() != 2 || m[0] < 1 || m[1] < 1) throw Error("codebook_score: the measured map must be [R, C], got " + shape_str(m));
    check_window("codebook_score", m[0], m[1]);
    const Shape want{in[0].shape[0] * in[1].shape[0]};
    if (in[3].shape != want)
        throw Error("codebook_score: the window minima must be " + shape_str(want) + " (one per hypothesis), got " + shape_str(in[3].shape));
    if (in[4].shape != Shape{1}) throw Error("codebook_score: the press must be [1], got " + shape_str(in[4].shape));
    score_params(p, G, m[0], m[1]);
    quadratic_of(p);
    return {TensorDesc{want}};
}

void score_cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const Book b = book_of(in[0]->shape, in[1]->shape, p, in[2]->shape[0], in[2]->shape[1]);
    const book::Basis basis = book::error_basis(b.s.R, b.s.C, quadratic_of(p));
    const float press = in[4]->data[0];
    for (int64_t i = 0; i < b.S; ++i)
        for (int64_t j = 0; j < b.NS; ++j) {
            const size_t h = size_t(i * b.NS + j);
            out[0]->data[h] = book::score_hypothesis(b.s, basis, &in[0]->data[size_t(i * b.stride)], in[1]->data[size_t(2 * j)],
                                                     in[1]->data[size_t(2 * j + 1)], in[2]->data.data(), in[3]->data[h], press);
        }
}

constexpr int64_t kUnrolledCells = 64;

void score_gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const Book b = book_of(a.in[0].shape, a.in[1].shape, a.params, a.in[2].shape[0], a.in[2].shape[1]);
    const book::ScoreParams& s = b.s;
    struct {
        WindowPush w;
        float weight;
        book::Basis basis;
    } push{{int32_t(b.S * b.NS), int32_t(b.NS), s.G, s.R, s.C, s.inv_cell, s.win, s.cap}, s.weight,
           book::error_basis(s.R, s.C, quadratic_of(a.params))};
    static_assert(sizeof(push) == 17 * 4, "the shader's push constants");
    const uint32_t local = elementwise_local_size(d), groups = grid_groups(uint64_t(push.w.H), local, d);
    const uint64_t strides = (uint64_t(push.w.H) + uint64_t(groups) * local - 1) / (uint64_t(groups) * local);
    check_loop_budget(d, strides * (uint64_t(s.R) * uint64_t(s.C) + uint64_t(s.R) + 2), "codebook_score");
    // A small window's rows and columns as specialization constants (a pipeline per window
    // size): its loops unroll and the measured map's reads get constant offsets. The shipped
    // 3 mm cells (5 x 7) score a touch in 19.5-20 ms instead of 23 (docs/render_compare.md);
    // a 15 x 20 window stays a loop (code size).
    const bool fixed = int64_t(s.R) * s.C <= kUnrolledCells;
    // The quads, spins and window minima as texel buffers where the device allows (gathers
    // on a CPU driver; param texel = 0 forces storage buffers).
    const bool texel = texels_allowed(a, {uint64_t(numel(a.in[0].shape)) / 4, uint64_t(numel(a.in[1].shape)),
                                          uint64_t(numel(a.in[3].shape))});
    const VkFormat f1 = texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED;
    const uint32_t rows = uint32_t(fixed ? s.R : 0), cols = uint32_t(fixed ? s.C : 0);
    a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{texel ? "codebook_score" : "codebook_score_ssbo", 6,
                                                          uint32_t(sizeof(push)), {local, rows, cols}, texel ? 0xbu : 0u}),
                   {{a.in[0].view, rt::Access::Read, texel ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_UNDEFINED},
                    {a.in[1].view, rt::Access::Read, f1}, {a.in[2].view, rt::Access::Read},
                    {a.in[3].view, rt::Access::Read, f1}, {a.in[4].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), groups);
}

}  // namespace

const OpDef op_codebook_render{"codebook_render", render_infer, render_cpu, render_gpu, 0,
                               {"G", "cell", "splat", "cap", "facing", "origin_x", "origin_y", "origin_z", "coarse", "nx", "ny", "nz", "max_bin"}};
const OpDef op_codebook_window_min{"codebook_window_min", window_min_infer, window_min_cpu, window_min_gpu, 0, {"rows", "cols", "cell", "win", "cap"}};
const OpDef op_codebook_score{"codebook_score", score_infer, score_cpu, score_gpu, 0,
                               {"cell", "win", "cap", "weight", "quadratic", "texel"}};

}  // namespace vtloc::ops
