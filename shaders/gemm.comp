#version 450
#extension GL_GOOGLE_include_directive : require
// C[m][n] = act(sum_k A[m][k] * W[n][k] + bias[n]) — PyTorch Linear, weight stored [N][K].
// Each workgroup computes a BM x BN block of C, walking K in BK-deep slabs staged
// through shared memory; each thread accumulates a TM x TN block in registers.
// All tile sizes are specialization constants chosen by the host from device limits.
layout(local_size_x_id = 0) in;  // = (BM / TM) * (BN / TN)
layout(constant_id = 1) const uint BM = 64;
layout(constant_id = 2) const uint BN = 64;
layout(constant_id = 3) const uint BK = 16;
layout(constant_id = 4) const uint TM = 4;
layout(constant_id = 5) const uint TN = 4;
#include "act.glsl"

layout(std430, binding = 0) readonly buffer A_ { float A[]; };
layout(std430, binding = 1) readonly buffer W_ { float W[]; };
layout(std430, binding = 2) readonly buffer Bias_ { float bias[]; };
layout(std430, binding = 3) writeonly buffer C_ { float C[]; };
layout(push_constant) uniform Push { uint M; uint N; uint K; uint has_bias; uint act; float slope; } p;

shared float As[BK * BM];  // k-major so the inner loop reads consecutive m / n
shared float Ws[BK * BN];

void main() {
    const uint TX = BN / TN;
    const uint TY = BM / TM;
    const uint threads = TX * TY;
    uint tid = gl_LocalInvocationID.x;
    uint tx = tid % TX, ty = tid / TX;
    uint m0 = gl_WorkGroupID.y * BM, n0 = gl_WorkGroupID.x * BN;

    float acc[TM * TN];
    for (uint i = 0; i < TM * TN; ++i) acc[i] = 0.0;

    for (uint k0 = 0; k0 < p.K; k0 += BK) {
        // Neighbouring threads load neighbouring k: contiguous reads of a row.
        for (uint i = tid; i < BM * BK; i += threads) {
            uint r = i / BK, kk = i % BK;
            uint gm = m0 + r, gk = k0 + kk;
            As[kk * BM + r] = (gm < p.M && gk < p.K) ? A[gm * p.K + gk] : 0.0;
        }
        for (uint i = tid; i < BN * BK; i += threads) {
            uint r = i / BK, kk = i % BK;
            uint gn = n0 + r, gk = k0 + kk;
            Ws[kk * BN + r] = (gn < p.N && gk < p.K) ? W[gn * p.K + gk] : 0.0;
        }
        barrier();
        for (uint kk = 0; kk < BK; ++kk) {
            float a[TM];
            float w[TN];
            for (uint i = 0; i < TM; ++i) a[i] = As[kk * BM + ty + i * TY];
            for (uint j = 0; j < TN; ++j) w[j] = Ws[kk * BN + tx + j * TX];
            for (uint i = 0; i < TM; ++i)
                for (uint j = 0; j < TN; ++j) acc[i * TN + j] = fma(a[i], w[j], acc[i * TN + j]);
        }
        barrier();
    }

    for (uint i = 0; i < TM; ++i) {
        uint m = m0 + ty + i * TY;
        if (m >= p.M) continue;
        for (uint j = 0; j < TN; ++j) {
            uint n = n0 + tx + j * TX;
            if (n >= p.N) continue;
            float v = acc[i * TN + j] + (p.has_bias != 0u ? bias[n] : 0.0);
            C[m * p.N + n] = apply_act(v, p.act, p.slope);
        }
    }
}
