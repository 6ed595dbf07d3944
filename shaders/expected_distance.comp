#version 450
// cost[j] = sum_s w[s] ||p_s - a_j|| (the Bayes risk of answering a_j for the
// distance error), one answer j per invocation; the (p_s, w_s) stream through
// shared memory in tiles of the workgroup size.
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer Pts_ { float pts[]; };  // [S, 3]
layout(std430, binding = 1) readonly buffer W_ { float w[]; };      // [S]
layout(std430, binding = 2) readonly buffer A_ { float ans[]; };    // [A, 3]
layout(std430, binding = 3) writeonly buffer Out_ { float cost[]; };
layout(push_constant) uniform Push { uint S; uint A; } p;

shared vec4 tile[gl_WorkGroupSize.x];

void main() {
    const uint L = gl_WorkGroupSize.x, tid = gl_LocalInvocationID.x;
    const uint j = gl_WorkGroupID.x * L + tid;
    vec3 pj = j < p.A ? vec3(ans[3u * j], ans[3u * j + 1u], ans[3u * j + 2u]) : vec3(0.0);
    float acc = 0.0;
    for (uint base = 0u; base < p.S; base += L) {
        uint s = base + tid;
        tile[tid] = s < p.S ? vec4(pts[3u * s], pts[3u * s + 1u], pts[3u * s + 2u], w[s]) : vec4(0.0);
        barrier();
        uint n = min(L, p.S - base);
        for (uint i = 0u; i < n; ++i) {
            vec3 e = tile[i].xyz - pj;
            acc += tile[i].w * sqrt((e.x * e.x + e.y * e.y) + e.z * e.z);
        }
        barrier();
    }
    if (j < p.A) cost[j] = acc;
}
