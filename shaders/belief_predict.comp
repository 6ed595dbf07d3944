#version 450
// One touch of the multi-contact belief (SPEC 6) in log space, one candidate i per
// thread: out[i] = loglik_t(i) + (FIRST ? -log M
//   : logsumexp_j(-||c_i - (c_j + d)||^2 / (2 sigma_m^2) + prev[j])),
// loglik_t(i) = -||c_i - c^p_t||^2 / (2 sigma^2). The O(M^2) sum streams the moved
// candidates c_j + d and prev[j] through shared memory in tiles of L, with an
// online (running-max) logsumexp so that no weight underflows.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool FIRST = false;

layout(std430, binding = 0) readonly buffer Cand_ { float cand[]; };      // [M, 3]
layout(std430, binding = 1) readonly buffer Contacts_ { float cp[]; };    // [T, 3]
layout(std430, binding = 2) readonly buffer Motions_ { float motion[]; }; // [T - 1, 3]
layout(std430, binding = 3) readonly buffer Prev_ { float prev[]; };      // [M], normalised log belief
layout(std430, binding = 4) writeonly buffer Out_ { float outv[]; };      // [M]
layout(push_constant) uniform Push { uint M; uint t; float inv2s2; float inv2sm2; } p;

shared vec4 tile[gl_WorkGroupSize.x];  // moved c_j (xyz), prev[j] (w)

float sq(vec3 e) { return (e.x * e.x + e.y * e.y) + e.z * e.z; }

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const uint i = gl_WorkGroupID.x * L + tid;
    vec3 ci = i < p.M ? vec3(cand[3u * i], cand[3u * i + 1u], cand[3u * i + 2u]) : vec3(0.0);
    float v;
    if (FIRST) {
        v = -log(float(p.M));
    } else {
        vec3 d = vec3(motion[3u * (p.t - 1u)], motion[3u * (p.t - 1u) + 1u], motion[3u * (p.t - 1u) + 2u]);
        float m = -1.0 / 0.0, s = 0.0;
        for (uint j0 = 0u; j0 < p.M; j0 += L) {
            uint j = j0 + tid;
            if (j < p.M) tile[tid] = vec4(vec3(cand[3u * j], cand[3u * j + 1u], cand[3u * j + 2u]) + d, prev[j]);
            barrier();
            uint n = min(L, p.M - j0);
            for (uint k = 0u; k < n; ++k) {
                float a = tile[k].w - sq(ci - tile[k].xyz) * p.inv2sm2;
                if (a > m) {
                    s = s * exp(m - a) + 1.0;
                    m = a;
                } else {
                    s += exp(a - m);
                }
            }
            barrier();
        }
        v = m + log(s);
    }
    vec3 e = ci - vec3(cp[3u * p.t], cp[3u * p.t + 1u], cp[3u * p.t + 2u]);
    if (i < p.M) outv[i] = v - sq(e) * p.inv2s2;
}
