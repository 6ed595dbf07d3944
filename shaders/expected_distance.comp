#version 450
// cost[j] = sum_s w[s] ||p_s - a_j|| (the Bayes risk of answering a_j for the
// distance error), one answer j per invocation; the (p_s, w_s) stream through
// shared memory in tiles of the workgroup size. Each tile keeps only its nonzero
// weights, in order: once the filter has seen a few touches most samples' belief
// underflows to 0, and skipping a term w * d = 0 leaves the float sum bit for bit
// as it was.
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer Pts_ { float pts[]; };  // [S, 3]
layout(std430, binding = 1) readonly buffer W_ { float w[]; };      // [S]
layout(std430, binding = 2) readonly buffer A_ { float ans[]; };    // [A, 3]
layout(std430, binding = 3) writeonly buffer Out_ { float cost[]; };
layout(push_constant) uniform Push { uint S; uint A; } p;

shared vec4 tile[gl_WorkGroupSize.x];
shared uint kept;  // the tile's nonzero weights, at its front

void main() {
    const uint L = gl_WorkGroupSize.x, tid = gl_LocalInvocationID.x;
    const uint j = gl_WorkGroupID.x * L + tid;
    vec3 pj = j < p.A ? vec3(ans[3u * j], ans[3u * j + 1u], ans[3u * j + 2u]) : vec3(0.0);
    float acc = 0.0;
    for (uint base = 0u; base < p.S; base += L) {
        uint s = base + tid;
        tile[tid] = s < p.S ? vec4(pts[3u * s], pts[3u * s + 1u], pts[3u * s + 2u], w[s]) : vec4(0.0);
        barrier();
        if (tid == 0u) {  // a serial pass: L reads of shared memory, order kept
            uint n = 0u;
            for (uint i = 0u; i < min(L, p.S - base); ++i)
                if (tile[i].w != 0.0) tile[n++] = tile[i];
            kept = n;
        }
        barrier();
        const uint n = kept;
        for (uint i = 0u; i < n; ++i) {
            vec3 e = tile[i].xyz - pj;
            acc += tile[i].w * sqrt((e.x * e.x + e.y * e.y) + e.z * e.z);
        }
        barrier();
    }
    if (j < p.A) cost[j] = acc;
}
