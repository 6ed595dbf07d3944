// belief: multi-contact belief over the candidates (SPEC 6, weights_tools/post.py
// multi_contact_belief): for the last `window` touches (0 = all) the belief starts
// uniform, the first of them has no motion step, later ones apply the prediction
// b'(i) = sum_j exp(-||c_i - (c_j + d_t)||^2 / (2 sigma_m^2)) b(j); then
// b ∝ exp(-||c^p_t - c_i||^2 / (2 sigma^2)) b'. Computed in log space.
// -> shaders/belief_predict.comp (the O(M^2) step, tiled) and
// shaders/belief_norm.comp (logsumexp normalisation, one workgroup), per touch.
// Inputs (normalised frame): candidates [M, 3], contacts c^p_t [T, 3], motions
// [T - 1, 3] (motions[t-1]: sensor displacement from touch t-1 to t, / scale).
// Params: sigma (0.2), sigma_m (0.05), window (4). Outputs: belief [M] (sums to 1)
// and log belief [M]; the GPU passes ping-pong between the two.
#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

struct Settings {
    double sigma, sigma_m;
    int64_t window;
};
Settings settings(const Params& p) {
    Settings s{p.get("sigma", 0.2), p.get("sigma_m", 0.05), int64_t(p.get("window", 4))};
    if (!(s.sigma > 0) || !(s.sigma_m > 0)) throw Error("sigma and sigma_m must be positive");
    if (s.window < 0 || double(s.window) != p.get("window", 4)) throw Error("window must be an integer >= 0 (0 = all touches)");
    return s;
}
int64_t first_touch(int64_t T, int64_t window) { return window == 0 ? 0 : std::max<int64_t>(0, T - window); }

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 3, 3);
    expect_f32(in);
    settings(p);
    const Shape &c = in[0].shape, &cp = in[1].shape, &d = in[2].shape;
    if (c.size() != 2 || c[1] != 3 || c[0] == 0) throw Error("candidates must be [M > 0, 3], got " + shape_str(c));
    if (cp.size() != 2 || cp[1] != 3 || cp[0] == 0) throw Error("contacts must be [T > 0, 3], got " + shape_str(cp));
    if (d != Shape{cp[0] - 1, 3})
        throw Error("motions must be [T - 1, 3] = " + shape_str({cp[0] - 1, 3}) + " for " + std::to_string(cp[0]) +
                    " contacts, got " + shape_str(d));
    to_u32(3 * c[0], "candidate array size");
    return {TensorDesc{{c[0]}}, TensorDesc{{c[0]}}};
}

double sq(const float* a, const double* b) {
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return (dx * dx + dy * dy) + dz * dz;
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const Settings st = settings(p);
    for (int i = 0; i < 3; ++i)
        for (float v : in[size_t(i)]->data)
            if (!std::isfinite(v)) throw Error(std::string("belief: the ") + (i == 0 ? "candidates" : i == 1 ? "contacts" : "motions") + " hold NaN or inf");
    const HostTensor &c = *in[0], &cp = *in[1], &d = *in[2];
    const int64_t M = c.shape[0], T = cp.shape[0];
    std::vector<double> logb(static_cast<size_t>(M), -std::log(double(M))), next(static_cast<size_t>(M));
    for (int64_t t = first_touch(T, st.window); t < T; ++t) {
        if (t > first_touch(T, st.window)) {
            for (int64_t i = 0; i < M; ++i) {
                double m = -std::numeric_limits<double>::infinity(), s = 0.0;
                std::vector<double> a(static_cast<size_t>(M));
                for (int64_t j = 0; j < M; ++j) {
                    double moved[3];
                    for (int k = 0; k < 3; ++k) moved[k] = double(c.data[size_t(3 * j + k)]) + d.data[size_t(3 * (t - 1) + k)];
                    a[size_t(j)] = logb[size_t(j)] - sq(&c.data[size_t(3 * i)], moved) / (2 * st.sigma_m * st.sigma_m);
                    m = std::max(m, a[size_t(j)]);
                }
                for (double v : a) s += std::exp(v - m);
                next[size_t(i)] = m + std::log(s);
            }
            logb.swap(next);
        }
        const double ct[3] = {cp.data[size_t(3 * t)], cp.data[size_t(3 * t + 1)], cp.data[size_t(3 * t + 2)]};
        for (int64_t i = 0; i < M; ++i) logb[size_t(i)] -= sq(&c.data[size_t(3 * i)], ct) / (2 * st.sigma * st.sigma);
        double m = *std::max_element(logb.begin(), logb.end()), s = 0.0;
        for (double v : logb) s += std::exp(v - m);
        for (double& v : logb) v -= m + std::log(s);
    }
    for (int64_t i = 0; i < M; ++i) {
        out[0]->data[size_t(i)] = float(std::exp(logb[size_t(i)]));
        out[1]->data[size_t(i)] = float(logb[size_t(i)]);
    }
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const Settings st = settings(a.params);
    const uint32_t M = uint32_t(a.in[0].shape[0]);
    const int64_t T = a.in[1].shape[0], first = first_touch(T, st.window);
    uint32_t local = elementwise_local_size(d);
    while (local > 1 && local * 16 > d.max_shared_memory) local /= 2;
    const uint64_t groups = (M + local - 1) / local;
    if (groups > d.max_workgroup_count[0]) throw Error("too many candidates for the belief on this device");
    // Touch t writes buffer (T - 1 - t) % 2: the last one lands in the log output
    // (1) and its exponential in the belief (0).
    const rt::BufferView* buf[2] = {&a.out[0].view, &a.out[1].view};
    for (int64_t t = first; t < T; ++t) {
        const rt::BufferView& dst = *buf[1 - (T - 1 - t) % 2];
        const rt::BufferView& src = *buf[(T - 1 - t) % 2];
        const bool is_first = t == first;
        struct { uint32_t M, t; float inv2s2, inv2sm2; } push{
            M, uint32_t(t), float(1.0 / (2 * st.sigma * st.sigma)), float(1.0 / (2 * st.sigma_m * st.sigma_m))};
        // Motions may be empty (T = 1): any read-only buffer fills an unused binding.
        const rt::BufferView& motions = T > 1 ? a.in[2].view : a.in[0].view;
        a.seq.dispatch(pipeline(a.ctx, "belief_predict", 5, 16, {local, is_first}),
                       {{a.in[0].view, rt::Access::Read}, {a.in[1].view, rt::Access::Read}, {motions, rt::Access::Read},
                        {is_first ? a.in[0].view : src, rt::Access::Read}, {dst, rt::Access::Write}},
                       &push, sizeof(push), uint32_t(groups));
        const bool last = t + 1 == T;
        uint32_t norm_local = elementwise_local_size(d);
        while (norm_local > 1 && norm_local * 4 > d.max_shared_memory) norm_local /= 2;
        a.seq.dispatch(pipeline(a.ctx, "belief_norm", 2, 4, {norm_local, last}),
                       {{dst, rt::Access::ReadWrite}, {last ? src : a.in[0].view, last ? rt::Access::Write : rt::Access::Read}},
                       &M, 4, 1);
    }
}

}  // namespace

const OpDef op_belief{"belief", infer, cpu, gpu, 0, {"sigma", "sigma_m", "window"}};

}  // namespace vtloc::ops
