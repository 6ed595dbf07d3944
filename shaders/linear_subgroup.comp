#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// linear's y = act(x W^T + b) (W [N][K], PyTorch's layout) without shared memory:
// a thread owns one row of x and TN consecutive outputs (workgroup y picks the
// block, TN <= the subgroup size). Per block of 4 inputs, lane l fetches W's
// vec4 for output n0 + l % TN and every lane takes the TN vec4s from their
// lanes by subgroupShuffle; x's vec4 is the thread's own fetch. Why: where a
// shared-memory load is a loop over the lanes (CPU drivers), gemm.comp's tiles
// cost more than its multiply-adds; here a weight costs one gather per
// subgroup. Needs K % 4 == 0 (x and W read as vec4 texels). Rows past the end
// compute on the last row and store nothing, so every lane takes part in every
// shuffle.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint TN = 8;
#include "act.glsl"

layout(binding = 0) uniform samplerBuffer X;  // [M][K] as vec4s
layout(binding = 1) uniform samplerBuffer W;  // [N][K] as vec4s
layout(std430, binding = 2) readonly buffer Bias_ { float bias[]; };
layout(std430, binding = 3) writeonly buffer Y_ { float Y[]; };
layout(push_constant) uniform Push { uint M; uint N; uint K; uint has_bias; uint act; float slope; } p;

void main() {
    const uint m_all = gl_GlobalInvocationID.x, m = min(m_all, p.M - 1u);
    const uint n0 = gl_WorkGroupID.y * TN, KB = p.K / 4u;
    const uint nl = min(n0 + gl_SubgroupInvocationID % TN, p.N - 1u);  // the output row this lane fetches
    float acc[TN];
    for (uint j = 0u; j < TN; ++j) acc[j] = 0.0;
    for (uint kb = 0u; kb < KB; ++kb) {
        const vec4 x = texelFetch(X, int(m * KB + kb));
        const vec4 wl = texelFetch(W, int(nl * KB + kb));
        for (uint j = 0u; j < TN; ++j) acc[j] += dot(x, subgroupShuffle(wl, j));
    }
    if (m_all >= p.M) return;
    for (uint j = 0u; j < TN; ++j) {
        const uint n = n0 + j;
        if (n < p.N) Y[m * p.N + n] = apply_act(acc[j] + (p.has_bias != 0u ? bias[n] : 0.0), p.act, p.slope);
    }
}
