#version 450
#extension GL_GOOGLE_include_directive : require
// One row chunk of Y[m][n] = act(sum_k X[m][k] * W[k][n]) with W stored [K][N]
// (GMA's einsum; N = N^d * C^d). W arrives in row chunks that each fit one
// binding; chunk c covers rows k_off .. k_off + Kc - 1 and adds its partial sum
// to Y (accumulate = 1) unless it is the first; the last applies act.
// Thread = V consecutive columns (V = 4 when N % 4 == 0: 16-byte loads), so each
// W row is read contiguously across the workgroup, exactly once in all. X's
// values, the same for every thread, are staged through shared memory in slabs
// of TK (one slab for the paper's K = 256: two barriers per column block).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint V = 4;     // columns per thread: 4 or 1
layout(constant_id = 2) const uint TK = 256;  // X values staged per slab
#include "act.glsl"

layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(std430, binding = 1) readonly buffer W_ { float W[]; };
layout(std430, binding = 1) readonly buffer W4_ { vec4 W4[]; };  // the same buffer, V = 4
layout(std430, binding = 2) buffer Y_ { float Y[]; };
layout(std430, binding = 2) buffer Y4_ { vec4 Y4[]; };
layout(push_constant) uniform Push {
    uint N; uint K; uint k_off; uint Kc; uint accumulate; uint last; uint act; float slope;
} p;

shared float xs[TK];

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const uint m = gl_WorkGroupID.y;
    const uint NV = p.N / V;  // vectors per row
    const uint xb = m * p.K + p.k_off;
    // Grid-stride over column blocks; the bound is uniform across the workgroup,
    // so the barriers inside stay in uniform control flow.
    for (uint n0 = gl_WorkGroupID.x * L; n0 < NV; n0 += gl_NumWorkGroups.x * L) {
        const uint n = n0 + tid;
        vec4 acc = vec4(0.0);
        for (uint k0 = 0u; k0 < p.Kc; k0 += TK) {
            const uint slab = min(TK, p.Kc - k0);
            for (uint i = tid; i < slab; i += L) xs[i] = X[xb + k0 + i];
            barrier();
            if (n < NV)
                for (uint i = 0u; i < slab; ++i) {
                    uint k = k0 + i;
                    if (V == 4u) acc = fma(vec4(xs[i]), W4[k * NV + n], acc);
                    else acc.x = fma(xs[i], W[k * NV + n], acc.x);
                }
            barrier();
        }
        if (n >= NV) continue;
        if (V == 4u) {
            if (p.accumulate != 0u) acc += Y4[m * NV + n];
            if (p.last != 0u)
                for (int j = 0; j < 4; ++j) acc[j] = apply_act(acc[j], p.act, p.slope);
            Y4[m * NV + n] = acc;
        } else {
            if (p.accumulate != 0u) acc.x += Y[m * NV + n];
            Y[m * NV + n] = p.last != 0u ? apply_act(acc.x, p.act, p.slope) : acc.x;
        }
    }
}
