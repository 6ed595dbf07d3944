// Body of log_softmax.comp (the score as a texel buffer) and log_softmax_ssbo.comp
// (a storage buffer, past the device's texel limit); they declare binding 0 and LOAD_V.
// log = v - logsumexp(v), prob = exp(log), in two dispatches of G workgroups, each over
// its own chunk of C scores (engine/ops/log_softmax.cpp):
//   PASS 0: the chunk's max m_g and sum of exp(v - m_g), each a tree in shared memory,
//           into part[2 g], part[2 g + 1];
//   PASS 1: each workgroup combines the G pairs (lse = m + log(sum s_g exp(m_g - m)), by
//           the same trees everywhere), then writes its chunk's log and prob.
// One workgroup was one thread of a CPU driver, and the filter's 120,000 scores took it
// 1.4 ms (2.9 ms with AVX2 only, where a storage read at a lane's own offset stalls).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int PASS = 0;

layout(std430, binding = 1) writeonly buffer Log_ { float logp[]; };
layout(std430, binding = 2) writeonly buffer Prob_ { float prob[]; };
layout(std430, binding = 3) buffer Part_ { float part[]; };  // [G, 2]: max, sum of exp
layout(push_constant) uniform Push { uint M; uint C; uint G; } p;

shared float red[gl_WorkGroupSize.x];

// Reduces red[] to red[0] (sum or max); the workgroup size need not be a power of two.
void reduce(bool is_max) {
    const uint tid = gl_LocalInvocationID.x;
    for (uint width = gl_WorkGroupSize.x; width > 1u;) {
        uint half_w = (width + 1u) / 2u;
        if (tid < width - half_w)
            red[tid] = is_max ? max(red[tid], red[tid + half_w]) : red[tid] + red[tid + half_w];
        width = half_w;
        barrier();
    }
}

// v's max (or sum) over the workgroup, the same value in every invocation.
float workgroup_all(float v, bool is_max) {
    red[gl_LocalInvocationID.x] = v;
    barrier();
    reduce(is_max);
    const float r = red[0];
    barrier();
    return r;
}

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x, g = gl_WorkGroupID.x;
    const uint lo = g * p.C, hi = min(p.M, lo + p.C);
    if (PASS == 0) {
        float m = -1.0 / 0.0;
        for (uint i = lo + tid; i < hi; i += L) m = max(m, LOAD_V(i));
        m = workgroup_all(m, true);
        float s = 0.0;
        // A chunk of -inf only (possible when others are finite) adds nothing, not NaN.
        if (m > -1.0 / 0.0)
            for (uint i = lo + tid; i < hi; i += L) s += exp(LOAD_V(i) - m);
        s = workgroup_all(s, false);
        if (tid == 0u) {
            part[2u * g] = m;
            part[2u * g + 1u] = s;
        }
    } else {
        // The G pairs combined by the workgroup's trees, the same order in every workgroup,
        // so every chunk subtracts the same lse.
        float m = -1.0 / 0.0;
        for (uint k = tid; k < p.G; k += L) m = max(m, part[2u * k]);
        m = workgroup_all(m, true);
        float s = 0.0;
        for (uint k = tid; k < p.G; k += L) {
            const float mk = part[2u * k];
            if (mk > -1.0 / 0.0) s += part[2u * k + 1u] * exp(mk - m);
        }
        const float lse = m + log(workgroup_all(s, false));
        for (uint i = lo + tid; i < hi; i += L) {
            const float l = LOAD_V(i) - lse;
            logp[i] = l;
            prob[i] = exp(l);
        }
    }
}
