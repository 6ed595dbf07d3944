// ilu: the whole ILU head (SPEC 2) fused -> shaders/ilu.comp, one dispatch, one
// workgroup (h is only C wide, so the iterations are latency-bound: keeping h and
// the gates in shared memory beats 10+ dispatches per iteration).
// Inputs: ft [1, C], fp [1, C], iters I32 [1] (N, read at run time),
//   convz.weight [C, 3C], convz.bias [C], convr.*, convq.*, head.0.weight [H, C],
//   head.0.bias [H], head.2.weight [3, H], head.2.bias [3].
// Param max_iters (0..64): outputs c [max_iters, 3] = c_1..c_N then zero rows,
// and contact [3] = c_N (0 for N = 0). N outside 0..max_iters is an error here;
// the shader clamps it (the host checks N before a run, see engine/model/heads.h).
#include <cmath>

#include "engine/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

constexpr int kMaxIters = 64;

void expect_shape(const TensorDesc& d, const Shape& want, const char* what) {
    if (d.shape != want) throw Error(std::string(what) + " is " + shape_str(d.shape) + ", expected " + shape_str(want));
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 13, 13);
    const double max_iters = p.get("max_iters", -1);
    if (!(max_iters >= 0 && max_iters <= kMaxIters) || max_iters != std::floor(max_iters))
        throw Error("max_iters must be an integer in 0..64, got " + std::to_string(max_iters));
    if (in[2].type != ElemType::I32 || in[2].shape != Shape{1})
        throw Error("iteration count must be an I32 [1] tensor, got " + std::string(elem_type_name(in[2].type)) +
                    " " + shape_str(in[2].shape));
    for (size_t i = 0; i < in.size(); ++i)
        if (i != 2 && in[i].type != ElemType::F32) throw Error("input " + std::to_string(i) + " must be F32");
    if (in[0].shape.empty()) throw Error("F^t must be [1, C]");
    const int64_t C = in[0].shape.back();
    if (numel(in[0].shape) != C || C == 0) throw Error("F^t must be one non-empty row [1, C], got " + shape_str(in[0].shape));
    expect_shape(in[1], in[0].shape, "F^p");
    for (int g = 0; g < 3; ++g) {
        expect_shape(in[size_t(3 + 2 * g)], {C, 3 * C}, "gate weight");
        expect_shape(in[size_t(4 + 2 * g)], {C}, "gate bias");
    }
    if (in[9].shape.size() != 2 || in[9].shape[1] != C || in[9].shape[0] == 0)
        throw Error("head.0.weight must be [H, " + std::to_string(C) + "], got " + shape_str(in[9].shape));
    const int64_t H = in[9].shape[0];
    expect_shape(in[10], {H}, "head.0.bias");
    expect_shape(in[11], {3, H}, "head.2.weight");
    expect_shape(in[12], {3}, "head.2.bias");
    return {TensorDesc{{int64_t(max_iters), 3}}, TensorDesc{{3}}};
}

// y = W[:, col0 : col0 + v.size()] v + b, W row-major with `stride` columns.
std::vector<double> matvec(const HostTensor& W, const HostTensor* b, int64_t stride, int64_t col0,
                           const std::vector<double>& v) {
    std::vector<double> y(static_cast<size_t>(W.shape[0]));
    for (size_t r = 0; r < y.size(); ++r) {
        double s = b ? b->data[r] : 0.0;
        for (size_t k = 0; k < v.size(); ++k) s += double(W.data[r * size_t(stride) + size_t(col0) + k]) * v[k];
        y[r] = s;
    }
    return y;
}

double sigmoid(double v) { return 1.0 / (1.0 + std::exp(-v)); }

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int max_iters = int(p.get("max_iters", 0));
    const int n = in[2]->int_at(0);
    if (n < 0 || n > max_iters)
        throw Error("ILU iteration count " + std::to_string(n) + " is outside 0.." + std::to_string(max_iters));
    const int64_t C = in[0]->shape.back();
    std::vector<double> h(static_cast<size_t>(C)), x(static_cast<size_t>(2 * C)), c(3, 0.0);
    for (int64_t i = 0; i < C; ++i) {
        double ft = in[0]->data[size_t(i)];
        h[size_t(i)] = std::tanh(ft);
        x[size_t(i)] = in[1]->data[size_t(i)];
        x[size_t(C + i)] = std::max(ft, 0.0);
    }
    std::vector<double> hx(static_cast<size_t>(3 * C)), rhx;
    std::fill(out[0]->data.begin(), out[0]->data.end(), 0.0f);
    for (int it = 0; it < n; ++it) {
        std::copy(h.begin(), h.end(), hx.begin());
        std::copy(x.begin(), x.end(), hx.begin() + C);
        std::vector<double> z = matvec(*in[3], in[4], 3 * C, 0, hx), r = matvec(*in[5], in[6], 3 * C, 0, hx);
        rhx = hx;
        for (int64_t i = 0; i < C; ++i) rhx[size_t(i)] = sigmoid(r[size_t(i)]) * h[size_t(i)];
        std::vector<double> q = matvec(*in[7], in[8], 3 * C, 0, rhx);
        for (int64_t i = 0; i < C; ++i) {
            double zi = sigmoid(z[size_t(i)]);
            h[size_t(i)] = (1.0 - zi) * h[size_t(i)] + zi * std::tanh(q[size_t(i)]);
        }
        std::vector<double> hid = matvec(*in[9], in[10], C, 0, h);
        for (double& v : hid) v = std::max(v, 0.0);
        std::vector<double> delta = matvec(*in[11], in[12], int64_t(hid.size()), 0, hid);
        for (int j = 0; j < 3; ++j) {
            c[size_t(j)] += delta[size_t(j)];
            out[0]->data[size_t(it * 3 + j)] = float(c[size_t(j)]);
        }
    }
    for (int j = 0; j < 3; ++j) out[1]->data[size_t(j)] = float(c[size_t(j)]);
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t C = to_u32(a.in[0].shape.back(), "ILU hidden size");
    const uint32_t H = to_u32(a.in[9].shape[0], "ILU head size");
    to_u32(int64_t(C) * C * 3, "ILU gate weight size");
    const uint32_t L = elementwise_local_size(d);
    // Lanes per row (a power of two dividing L). Param "lanes" overrides the
    // default of 8 (tests use it to cover both shader paths).
    uint32_t G = uint32_t(a.params.get("lanes", 8));
    while (G > 1 && L % G) G /= 2;
    const uint64_t shared = (9ull * C + H + L + 3) * 4;
    if (shared > d.max_shared_memory)
        throw Error("ILU with C = " + std::to_string(C) + " needs " + std::to_string(shared) +
                    " bytes of shared memory; the device has " + std::to_string(d.max_shared_memory));
    uint32_t max_iters = uint32_t(a.params.get("max_iters", 0));
    std::vector<rt::Binding> b;
    for (const GpuTensor& t : a.in) b.push_back({t.view, rt::Access::Read});
    for (const GpuTensor& t : a.out) b.push_back({t.view, rt::Access::Write});
    a.seq.dispatch(pipeline(a.ctx, "ilu", 15, 4, {L, C, H, G}), b, &max_iters, 4, 1);
}

}  // namespace

const OpDef op_ilu{"ilu", infer, cpu, gpu};

}  // namespace vtloc::ops
