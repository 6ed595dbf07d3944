// pose_evidence: the multi-touch filter's log score of every sensor-pose
// hypothesis (SPEC 6; docs/multitouch.md). Hypothesis h = sample * NS + spin;
// each term k carries it to another touch's pose (R rel_k, t + R trel_k) and adds
// that pose's geometry evidence (on the surface, axis along the inward normal)
// and/or a log field (a touch term, or the online filter's previous belief)
// read at the nearest hypothesis. own_field adds a field at h itself.
// Inputs: samples [S, 12] (point, 0, normal, 0, t1, 0), dense surface [D, 8] (point, the
// point's sample as a float (-1: none), outward normal, 0: two vec4 reads on the GPU),
// cells [V, 2] I32 (nearest dense point and its counterpart on a face turned the other
// way: pose_evidence.h), spins [NS, 2] (cos, sin of 2 pi j / NS, evenly spaced),
// terms [K, 16] (rel 9, trel 3, sigma_d, sigma_a, field, weight), fields
// [F, S * NS]. Output: score [S * NS]. -> shaders/pose_evidence.glsl (pose_evidence.comp:
// the tables as texel buffers; pose_evidence_ssbo.comp: past the texel limit)
// Terms are data on the device, so only the CPU reference can refuse a term naming a
// field past F; the shader reads nothing for one (no read out of bounds). The
// tracker never builds one.
#include <cmath>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/ops.h"
#include "engine/ops/pose_evidence.h"

namespace vtloc::ops {
namespace {

struct Setup {
    float press, log_floor, field_floor, voxel, own_weight;
    pose::V3 origin;
    int32_t nx, ny, nz, own_field, interleave;
};

int32_t int_param(const Params& p, const char* k, double fallback) {
    double v = p.get(k, fallback);
    if (!(v == std::floor(v)) || v < -1 || v > 2147483647.0) throw Error(std::string(k) + " must be an integer");
    return int32_t(v);
}

Setup setup(const Params& p) {
    Setup s{float(p.get("press", 0.8)), float(p.get("log_floor", -12)), float(p.get("field_floor", -30)),
            float(p.get("voxel", 1)), float(p.get("own_weight", 1)),
            {float(p.get("ox", 0)), float(p.get("oy", 0)), float(p.get("oz", 0))},
            int_param(p, "nx", 1), int_param(p, "ny", 1), int_param(p, "nz", 1), int_param(p, "own_field", -1),
            int_param(p, "interleave", 0)};
    if (!(s.voxel > 0) || !std::isfinite(s.voxel)) throw Error("voxel must be positive");
    if (s.nx < 1 || s.ny < 1 || s.nz < 1) throw Error("grid dims nx, ny, nz must be >= 1");
    if (s.interleave < 0 || s.interleave > 8) throw Error("interleave must be 0 (the device's) or 1-8");
    if (!std::isfinite(s.press) || !std::isfinite(s.log_floor) || !std::isfinite(s.field_floor))
        throw Error("press, log_floor and field_floor must be finite");
    return s;
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 6, 6);
    for (int i : {0, 1, 3, 4, 5})
        if (in[size_t(i)].type != ElemType::F32) throw Error("input " + std::to_string(i) + " must be F32");
    if (in[2].type != ElemType::I32) throw Error("cells must be I32");
    const Setup st = setup(p);
    const Shape &s = in[0].shape, &d = in[1].shape, &c = in[2].shape, &sp = in[3].shape, &k = in[4].shape,
                &f = in[5].shape;
    if (s.size() != 2 || s[1] != 12 || s[0] == 0)
        throw Error("samples must be [S > 0, 12] (point, 0, normal, 0, t1, 0), got " + shape_str(s));
    if (d.size() != 2 || d[1] != 8 || d[0] == 0)
        throw Error("dense surface must be [D > 0, 8] (point, sample, normal, 0), got " + shape_str(d));
    if (s[0] >= (int64_t(1) << 24)) throw Error("at most 2^24 samples (their indices are floats), got " + std::to_string(s[0]));
    const int64_t V = int64_t(st.nx) * st.ny * st.nz;
    if (c != Shape{V, 2}) throw Error("cells must be [nx*ny*nz, 2] = " + shape_str({V, 2}) + ", got " + shape_str(c));
    if (sp.size() != 2 || sp[1] != 2 || sp[0] == 0) throw Error("spins must be [NS > 0, 2], got " + shape_str(sp));
    if (k.size() != 2 || k[1] != 16) throw Error("terms must be [K, 16], got " + shape_str(k));
    const int64_t H = s[0] * sp[0];
    if (f.size() != 2 || f[1] != H)
        throw Error("fields must be [F, S * NS] = [F, " + std::to_string(H) + "], got " + shape_str(f));
    if (st.own_field >= f[0]) throw Error("own_field " + std::to_string(st.own_field) + " names no field");
    to_u32(H * f[0], "field array size");
    to_u32(2 * V, "grid size");
    return {TensorDesc{{H}}};
}

// The [D, 8] input as the mirror's [D, 6] points and [D] samples; indices are checked
// here (the GPU trusts them: the tracker builds them).
struct Tables {
    std::vector<float> samples, dense;
    std::vector<int32_t> dense_sample, cells;
};
pose::Grid grid_of(const std::vector<const HostTensor*>& in, const Setup& st, Tables& t) {
    const int64_t D = in[1]->shape[0], S = in[0]->shape[0];
    const float* d8 = in[1]->data.data();
    for (int64_t i = 0; i < D; ++i) {
        const float* r = d8 + i * 8;
        t.dense.insert(t.dense.end(), {r[0], r[1], r[2], r[4], r[5], r[6]});
        if (!(r[3] == std::floor(r[3]) && r[3] >= -1 && r[3] < float(S)))
            throw Error("dense point " + std::to_string(i) + " names sample " + std::to_string(r[3]) + " of " + std::to_string(S));
        t.dense_sample.push_back(int32_t(r[3]));
    }
    for (int64_t s = 0; s < S; ++s)
        for (int k = 0; k < 9; ++k) t.samples.push_back(in[0]->data[size_t(12 * s) + pose::padded_sample_offset(size_t(k))]);
    t.cells = in[2]->ints();
    for (size_t c = 0; c < t.cells.size(); ++c)
        if (t.cells[c] < -1 || t.cells[c] >= D)
            throw Error("cell " + std::to_string(c / 2) + " names dense point " + std::to_string(t.cells[c]) + " of " + std::to_string(D));
    return {t.dense.data(), t.dense_sample.data(), t.cells.data(), t.samples.data(), in[3]->data.data(),
            int32_t(in[3]->shape[0]), st.origin, st.voxel, st.nx, st.ny, st.nz};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const Setup st = setup(p);
    Tables tables;
    const pose::Grid g = grid_of(in, st, tables);
    const int64_t H = out[0]->shape[0], K = in[4]->shape[0], F = in[5]->shape[0];
    std::vector<pose::Term> terms;
    for (int64_t k = 0; k < K; ++k) {
        terms.push_back(pose::term_from_row(&in[4]->data[size_t(k * 16)]));
        if (terms.back().field >= F) throw Error("term " + std::to_string(k) + " names field " +
                                                 std::to_string(terms.back().field) + " of " + std::to_string(F));
    }
    // The shader finds a pose's nearest spin from atan2 (shaders/pose_evidence.comp), which
    // holds only for evenly spaced spins.
    const int64_t NS = in[3]->shape[0];
    for (int64_t j = 0; j < NS; ++j) {
        const double a = 2 * M_PI * double(j) / double(NS);
        if (!(std::abs(in[3]->data[size_t(2 * j)] - std::cos(a)) <= 1e-6 && std::abs(in[3]->data[size_t(2 * j + 1)] - std::sin(a)) <= 1e-6))
            throw Error("spin " + std::to_string(j) + " is not (cos, sin) of 2 pi * " + std::to_string(j) + " / " + std::to_string(NS));
    }
    const float* fields = in[5]->data.data();
    const float exp_floor = std::exp(st.log_floor);
    for (int64_t h = 0; h < H; ++h) {
        const pose::Frame f = pose::hypothesis_frame(g, h, st.press);
        float acc = st.own_field >= 0 ? st.own_weight * fields[int64_t(st.own_field) * H + h] : 0.0f;
        for (const pose::Term& t : terms) {
            const pose::Frame m = pose::moved(f, t);
            const int64_t cell = pose::cell_of(g, m.t);
            if (t.sigma_d > 0) acc += pose::geometry_log(g, cell, m, st.press, t.sigma_d, t.sigma_a, st.log_floor, exp_floor);
            if (t.field >= 0) {
                const int64_t hk = pose::nearest_hypothesis(g, cell, m.x, m.z);
                acc += t.weight * (hk < 0 ? st.field_floor : fields[int64_t(t.field) * H + hk]);
            }
        }
        out[0]->data[size_t(h)] = acc;
    }
}

// Hypotheses an invocation runs side by side: 3 on a CPU driver, where a term's three
// dependent gathers otherwise wait on memory one chain at a time (docs/multitouch.md,
// "Three hypotheses an invocation": 2 and 4 were slower on lavapipe); 1 on a GPU, which
// hides that latency with other invocations. Param interleave (1-8) forces it.
uint32_t interleave(const Setup& st, const rt::DeviceInfo& d) {
    return st.interleave > 0 ? uint32_t(st.interleave) : d.type == VK_PHYSICAL_DEVICE_TYPE_CPU ? 3u : 1u;
}

void gpu(const GpuOpArgs& a) {
    const Setup st = setup(a.params);
    const rt::DeviceInfo& d = a.ctx.info();
    const uint32_t H = uint32_t(a.out[0].shape[0]);
    const uint32_t K = uint32_t(a.in[4].shape[0]), F = uint32_t(a.in[5].shape[0]), NS = uint32_t(a.in[3].shape[0]);
    const uint32_t M = interleave(st, d);
    const uint32_t local = elementwise_local_size(d), groups = grid_groups((uint64_t(H) + M - 1) / M, local, d);
    const uint64_t strides = (uint64_t(H) + uint64_t(groups) * local * M - 1) / (uint64_t(groups) * local * M);
    check_loop_budget(d, strides * (uint64_t(K) * (NS + 2) + 4), "pose_evidence (hypotheses x terms x spins)");
    struct {
        float ox, oy, oz, inv_voxel;
        int32_t nx, ny, nz, n_spin;
        uint32_t H, K, F;
        int32_t own_field;
        float press, log_floor, field_floor, own_weight, exp_floor;
    } push{st.origin.x, st.origin.y, st.origin.z, 1.0f / st.voxel, st.nx, st.ny, st.nz, int32_t(NS), H, K, F,
           st.own_field, st.press, st.log_floor, st.field_floor, st.own_weight, std::exp(st.log_floor)};
    // Empty terms or fields: a small read-only input fills the unused binding (the spins:
    // at least one RGBA32F texel from NS = 2 on).
    const rt::BufferView& terms = K ? a.in[4].view : NS >= 2 ? a.in[3].view : a.in[0].view;
    const rt::BufferView& fields = F ? a.in[5].view : a.in[3].view;
    // The terms are always a texel buffer (binding 4, RGBA32F: a term's 16 floats in 4
    // texels; a window's few terms fit any device). The tables too (samples and dense
    // surface RGBA32F, cells R32I, spins and fields R32F: gathers on a CPU driver, where storage
    // reads at varying offsets are lane loops), unless one holds more texels than the
    // device allows or param texel = 0: then pose_evidence_ssbo.comp.
    const bool texel = texels_allowed(a, {uint64_t(a.in[0].shape[0]) * 3, uint64_t(a.in[1].shape[0]) * 2,
                                          uint64_t(a.in[2].shape[0]) * 2, 2 * uint64_t(NS), uint64_t(F) * H});
    const VkFormat f4 = texel ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_UNDEFINED;
    const rt::Access R = rt::Access::Read;
    // NS specialises the shader (shaders/pose_evidence.glsl).
    a.seq.dispatch(a.ctx.pipelines().get(rt::PipelineDesc{texel ? "pose_evidence" : "pose_evidence_ssbo", 7,
                                                          uint32_t(sizeof(push)), {local, NS, M}, texel ? 0x3fu : 0x10u}),
                   {{a.in[0].view, R, f4}, {a.in[1].view, R, f4},
                    {a.in[2].view, R, texel ? VK_FORMAT_R32_SINT : VK_FORMAT_UNDEFINED},
                    {a.in[3].view, R, texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED},
                    {terms, R, VK_FORMAT_R32G32B32A32_SFLOAT},
                    {fields, R, texel ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_UNDEFINED},
                    {a.out[0].view, rt::Access::Write}},
                   &push, sizeof(push), groups);
}

}  // namespace

const OpDef op_pose_evidence{"pose_evidence", infer, cpu, gpu, 0,
                             {"press", "log_floor", "field_floor", "ox", "oy", "oz", "voxel", "nx", "ny", "nz",
                              "own_field", "own_weight", "texel", "interleave"}};

}  // namespace vtloc::ops
