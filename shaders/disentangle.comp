#version 450
#extension GL_GOOGLE_include_directive : require
// One row chunk of Y[m][n] = act(sum_k X[m][k] * W[k][n]) with W stored [K][N]
// (GMA's einsum; N = N^d * C^d). W arrives in row chunks that each fit one
// binding; chunk c covers rows k_off .. k_off + Kc - 1 and adds its partial sum
// to Y (accumulate = 1) unless it is the first; the last applies act.
// Thread = V consecutive columns (V = 4 when N % 4 == 0: 16-byte loads) of MB
// rows of X (a batch's touches): each W value is loaded once per MB rows, which
// is what makes a batch cheaper than its touches one by one (W is 64 MiB at the
// paper's size). X's values, the same for every thread, are staged through shared
// memory in slabs of TK per row. Every Y value sums over k in the same order
// whatever MB is, so a batch gives its rows bit for bit what they get alone.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint V = 4;     // columns per thread: 4 or 1
layout(constant_id = 2) const uint TK = 256;  // X values staged per slab and row
layout(constant_id = 3) const uint MB = 1;    // rows of X per workgroup
#include "act.glsl"

layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(std430, binding = 1) readonly buffer W_ { float W[]; };
layout(std430, binding = 1) readonly buffer W4_ { vec4 W4[]; };  // the same buffer, V = 4
layout(std430, binding = 2) buffer Y_ { float Y[]; };
layout(std430, binding = 2) buffer Y4_ { vec4 Y4[]; };
layout(push_constant) uniform Push {
    uint N; uint K; uint k_off; uint Kc; uint accumulate; uint last; uint act; float slope; uint M;
} p;

shared float xs[MB * TK];

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const uint m0 = gl_WorkGroupID.y * MB;
    const uint rows = min(MB, p.M - m0);  // uniform across the workgroup
    const uint NV = p.N / V;  // vectors per row
    // Grid-stride over column blocks; the bound is uniform across the workgroup,
    // so the barriers inside stay in uniform control flow.
    for (uint n0 = gl_WorkGroupID.x * L; n0 < NV; n0 += gl_NumWorkGroups.x * L) {
        const uint n = n0 + tid;
        vec4 acc[MB];
        for (uint r = 0u; r < MB; ++r) acc[r] = vec4(0.0);
        for (uint k0 = 0u; k0 < p.Kc; k0 += TK) {
            const uint slab = min(TK, p.Kc - k0);
            for (uint r = 0u; r < rows; ++r)
                for (uint i = tid; i < slab; i += L) xs[r * TK + i] = X[(m0 + r) * p.K + p.k_off + k0 + i];
            barrier();
            if (n < NV)
                for (uint i = 0u; i < slab; ++i) {
                    const uint k = k0 + i;
                    const vec4 w = V == 4u ? W4[k * NV + n] : vec4(W[k * NV + n]);
                    for (uint r = 0u; r < MB; ++r)
                        if (r < rows) acc[r] = fma(vec4(xs[r * TK + i]), w, acc[r]);
                }
            barrier();
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
