#include "engine/ops/ilu_math.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"

namespace vtloc::ops::ilu_math {
namespace {

void expect_shape(const TensorDesc& d, const Shape& want, const char* what) {
    if (d.shape != want) throw Error(std::string(what) + " is " + shape_str(d.shape) + ", expected " + shape_str(want));
}

// y[r] = b[r] + sum_k W[r, col0 + k] v[k], W row-major with `stride` columns.
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

// At most 16 row blocks (64 rows) of h per lane: private arrays stay in registers.
constexpr uint32_t kMaxWaveBlocks = 16;

void choose_wave(const GpuOpArgs& a, Launch& l) {
    const rt::DeviceInfo& d = a.ctx.info();
    const double want = a.params.get("wave", 1);
    if (want == 0 || (want == 1 && !wave_by_default(d))) return;
    // A forced width (want >= 2) is a test's request: refuse it by name rather than
    // quietly run the other shader.
    auto no = [&](const std::string& why) {
        if (want >= 2) throw Error("the register-resident ILU (wave " + std::to_string(int(want)) + ") " + why);
    };
    const uint32_t sg = d.subgroup_size;
    if (!has_subgroup_shuffles(d)) return no("needs subgroup shuffles");
    if (l.C % 4 || l.H % 4)
        return no("needs C and H divisible by 4, got C = " + std::to_string(l.C) + ", H = " + std::to_string(l.H));
    const uint32_t L = want >= 2 ? uint32_t(want) : sg;
    if ((L & (L - 1)) || L > d.max_workgroup_size[0] || L > d.max_invocations)
        return no("needs a power-of-two workgroup size within the device's limits");
    if (uint64_t(l.C) * l.C * 3 / 4 > d.max_texel_elements || uint64_t(l.H) * 3 > d.max_texel_elements)
        return no("needs the gate weights to fit a texel buffer (" + std::to_string(d.max_texel_elements) + " texels)");
    const uint32_t RB = (l.C / 4 + L - 1) / L, HB = (l.H / 4 + L - 1) / L;
    if (RB > kMaxWaveBlocks || HB > kMaxWaveBlocks)
        return no("holds at most " + std::to_string(4 * kMaxWaveBlocks) + " rows per lane");
    if (uint64_t(l.C) * 4 + uint64_t(L) * 16 > d.max_shared_memory) return no("needs more shared memory");
    // Loop iterations of one invocation at max_iters (every loop counted, unrolled or not).
    const uint64_t CB = l.C / 4, per_iter = 3 * CB * (1 + RB) + CB * (1 + HB) + 4 * RB + 5 * HB + 16;
    const uint64_t iters = uint64_t(a.params.get("max_iters", 0));
    const uint64_t loops = iters * per_iter + 2 * CB * (1 + RB) + RB + HB + 3 * iters + 16;
    if (loops > kLoopIterationBudget)
        return no("would run " + std::to_string(iters * per_iter) + " loop iterations in one invocation, over the " +
                  std::to_string(kLoopIterationBudget) + " budget");
    l.wave = true;
    l.wave_L = L;
    l.RB = RB;
    l.HB = HB;
    l.wave_loops = loops;
}

}  // namespace

bool wave_by_default(const rt::DeviceInfo& d) { return d.type == VK_PHYSICAL_DEVICE_TYPE_CPU; }

int64_t check_inputs(const std::vector<TensorDesc>& in, bool batch) {
    if (in[2].type != ElemType::I32 || in[2].shape != Shape{1})
        throw Error("iteration count must be an I32 [1] tensor, got " + std::string(elem_type_name(in[2].type)) +
                    " " + shape_str(in[2].shape));
    for (size_t i = 0; i < 13; ++i)
        if (i != 2 && in[i].type != ElemType::F32) throw Error("input " + std::to_string(i) + " must be F32");
    if (in[0].shape.empty()) throw Error("F^t must be [1, C]");
    const int64_t C = in[0].shape.back();
    const bool rows = batch && in[0].shape.size() == 2 && in[0].shape[0] >= 1;
    if (C == 0 || (!rows && numel(in[0].shape) != C))
        throw Error(std::string("F^t must be ") + (batch ? "[B, C]" : "one non-empty row [1, C]") + ", got " +
                    shape_str(in[0].shape));
    if (numel(in[1].shape) != C || in[1].shape.back() != C)
        throw Error("F^p is " + shape_str(in[1].shape) + ", expected one row of " + std::to_string(C));
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
    return C;
}

State init(const std::vector<const HostTensor*>& in, int64_t row) {
    const int64_t C = in[0]->shape.back();
    State s;
    s.h.resize(size_t(C));
    std::vector<double> x(size_t(2 * C));
    for (int64_t i = 0; i < C; ++i) {
        double ft = in[0]->data[size_t(row * C + i)];
        s.h[size_t(i)] = std::tanh(ft);
        x[size_t(i)] = in[1]->data[size_t(i)];
        x[size_t(C + i)] = std::max(ft, 0.0);
    }
    for (int g = 0; g < 3; ++g) {
        std::vector<double> part = matvec(*in[size_t(3 + 2 * g)], in[size_t(4 + 2 * g)], 3 * C, C, x);
        s.gx.insert(s.gx.end(), part.begin(), part.end());
    }
    return s;
}

void iterate(const std::vector<const HostTensor*>& in, State& s) {
    const int64_t C = int64_t(s.h.size());
    std::vector<double> z = matvec(*in[3], nullptr, 3 * C, 0, s.h), r = matvec(*in[5], nullptr, 3 * C, 0, s.h);
    std::vector<double> rh(s.h.size());
    for (int64_t i = 0; i < C; ++i) rh[size_t(i)] = sigmoid(r[size_t(i)] + s.gx[size_t(C + i)]) * s.h[size_t(i)];
    std::vector<double> q = matvec(*in[7], nullptr, 3 * C, 0, rh);
    for (int64_t i = 0; i < C; ++i) {
        double zi = sigmoid(z[size_t(i)] + s.gx[size_t(i)]);
        s.h[size_t(i)] = (1.0 - zi) * s.h[size_t(i)] + zi * std::tanh(q[size_t(i)] + s.gx[size_t(2 * C + i)]);
    }
    std::vector<double> hid = matvec(*in[9], in[10], C, 0, s.h);
    for (double& v : hid) v = std::max(v, 0.0);
    std::vector<double> delta = matvec(*in[11], in[12], int64_t(hid.size()), 0, hid);
    for (int j = 0; j < 3; ++j) s.c[j] += delta[size_t(j)];
}

std::vector<rt::Binding> wave_bindings(const GpuOpArgs& a) {
    std::vector<rt::Binding> b;
    for (const GpuTensor& t : a.in) b.push_back({t.view, rt::Access::Read});
    for (const GpuTensor& t : a.out) b.push_back({t.view, rt::Access::Write});
    for (int i : {3, 5, 7, 9}) b[size_t(i)].texel_format = VK_FORMAT_R32G32B32A32_SFLOAT;
    b[11].texel_format = VK_FORMAT_R32_SFLOAT;
    return b;
}

Launch launch(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    Launch l;
    l.C = to_u32(a.in[0].shape.back(), "ILU hidden size");
    l.H = to_u32(a.in[9].shape[0], "ILU head size");
    to_u32(int64_t(l.C) * l.C * 3, "ILU gate weight size");
    l.L = elementwise_local_size(d);
    l.G = uint32_t(a.params.get("lanes", 8));  // a power of two dividing L
    while (l.G > 1 && l.L % l.G) l.G /= 2;
    const uint32_t sg = d.subgroup_size;
    l.subgroup = a.params.get("subgroup", 1) != 0 && (d.subgroup_ops & VK_SUBGROUP_FEATURE_SHUFFLE_BIT) &&
                 (d.subgroup_ops & VK_SUBGROUP_FEATURE_BASIC_BIT) && l.G > 1 && l.G <= sg && sg % l.G == 0 &&
                 l.L % sg == 0;
    choose_wave(a, l);
    const uint64_t shared = (9ull * l.C + l.H + l.L + 3) * 4;
    if (!l.wave && shared > d.max_shared_memory)
        throw Error("ILU with C = " + std::to_string(l.C) + " needs " + std::to_string(shared) +
                    " bytes of shared memory; the device has " + std::to_string(d.max_shared_memory));
    return l;
}

}  // namespace vtloc::ops::ilu_math
