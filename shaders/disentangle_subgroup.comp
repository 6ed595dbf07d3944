#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// disentangle.comp's row chunk of Y = act(X W) with no shared memory: X's
// values reach every lane by subgroupShuffle (each lane loads one per round of
// gl_SubgroupSize) and W is read as a texel buffer (vec4s of 4 columns, or
// floats when N % 4 != 0). Why: where a shared-memory or storage load is a loop
// over the lanes (CPU drivers), the slab reads cost more than the multiply-adds;
// a texel fetch is one gather and a shuffle by a shared index a broadcast. Sums
// over k in the same order as disentangle.comp whatever MB is, so a batch's rows
// are bit-identical to each row alone. Every lane takes part in every shuffle
// (columns past the end compute on a clamped column and do not store).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint V = 4;   // columns per thread: 4 or 1
layout(constant_id = 2) const uint MB = 1;  // rows of X per workgroup
#include "act.glsl"

layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(binding = 1) uniform samplerBuffer W;  // [Kc][N] as vec4s (V = 4) or floats
layout(std430, binding = 2) buffer Y_ { float Y[]; };
layout(std430, binding = 2) buffer Y4_ { vec4 Y4[]; };
layout(push_constant) uniform Push {
    uint N; uint K; uint k_off; uint Kc; uint accumulate; uint last; uint act; float slope; uint M;
} p;

void main() {
    const uint L = gl_WorkGroupSize.x, S = gl_SubgroupSize;
    const uint m0 = gl_WorkGroupID.y * MB;
    const uint rows = min(MB, p.M - m0);  // uniform across the workgroup
    const uint NV = p.N / V;
    for (uint n0 = gl_WorkGroupID.x * L; n0 < NV; n0 += gl_NumWorkGroups.x * L) {
        const uint n = n0 + gl_LocalInvocationID.x, nc = min(n, NV - 1u);
        vec4 acc[MB];
        for (uint r = 0u; r < MB; ++r) acc[r] = vec4(0.0);
        for (uint k0 = 0u; k0 < p.Kc; k0 += S) {
            const uint kl = k0 + gl_SubgroupInvocationID;
            float xl[MB];
            for (uint r = 0u; r < MB; ++r)
                xl[r] = r < rows && kl < p.Kc ? X[(m0 + r) * p.K + p.k_off + kl] : 0.0;
            const uint slab = min(S, p.Kc - k0);
            for (uint i = 0u; i < slab; ++i) {
                const vec4 w = V == 4u ? texelFetch(W, int((k0 + i) * NV + nc)) : vec4(texelFetch(W, int((k0 + i) * NV + nc)).x);
                for (uint r = 0u; r < MB; ++r) acc[r] = fma(vec4(subgroupShuffle(xl[r], i)), w, acc[r]);
            }
        }
        if (n >= NV) continue;
        for (uint r = 0u; r < rows; ++r) {
            const uint y = (m0 + r) * NV + n;
            vec4 v = acc[r];
            if (V == 4u) {
                if (p.accumulate != 0u) v += Y4[y];
                if (p.last != 0u)
                    for (int j = 0; j < 4; ++j) v[j] = apply_act(v[j], p.act, p.slope);
                Y4[y] = v;
            } else {
                if (p.accumulate != 0u) v.x += Y[y];
                Y[y] = p.last != 0u ? apply_act(v.x, p.act, p.slope) : v.x;
            }
        }
    }
}
