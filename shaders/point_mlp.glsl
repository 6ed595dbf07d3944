// Body of point_mlp.comp (texel-buffer reads of the activations and the cloud),
// point_mlp_ubo.comp (the same with the weights in a uniform buffer) and
// point_mlp_ssbo.comp (storage buffers, for tensors beyond the device's
// texel-buffer limit). They declare bindings 0, 1, 8, 9 and LOAD_A, LOAD_A4,
// LOAD_F, LOAD_F4.
//
// One PointNet++ MLP layer (1x1 conv, BatchNorm folded, act): out = act(A W + b)
// with W stored [K][N] (input-major, so 4 output channels are one vec4), and the
// grouping fused into the input or the neighbour max into the output:
// MODE 0: A is the previous layer's output, channel-major [K][M] (4 rows = one vec4).
// MODE 1 (gather): row m = (centre m / NS, slot) is [features of q, xyz of q - centre],
//   q = idx[m], read straight from the cloud (SPEC 2: features first).
// MODE 2 (group all): row m is [xyz of m, features of m] (xyz first, not centred).
// MODE 3 (per point): row m is [features of m, xyz of m] (MODE 1's columns for the
//   point itself, not centred: sa_gather.comp subtracts the centre's share).
// MAXPOOL: out[g][n] = max over the NS rows of group g (point-major [M / NS][N]);
//   else out is channel-major [N][M], the next layer's MODE 0 input.
// Register blocking and no shared memory: an invocation owns TM rows x TN channels
// (MAXPOOL: all rows of one group, TM at a time) and per input channel does TM x TN
// fmas from TM/4 + TN/4 vec4 loads. The channel block comes from gl_WorkGroupID.y,
// so the weight and bias loads are uniform across the workgroup (on GPUs a
// broadcast; on lavapipe one load and a broadcast only from a uniform buffer,
// point_mlp_ubo.comp: from a storage buffer it is still a loop over the lanes).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint TM = 4;   // rows per block, multiple of 4
layout(constant_id = 2) const uint TN = 16;  // channels per invocation, multiple of 4
layout(constant_id = 3) const uint MODE = 0;
layout(constant_id = 4) const bool MAXPOOL = false;
layout(constant_id = 5) const uint ACT = 0;  // act.glsl code
layout(constant_id = 6) const bool AVEC4 = true;  // MODE 0: rows as vec4 (M, and NS when MAXPOOL, % 4 == 0)
layout(constant_id = 7) const bool FVEC4 = true;  // MODE 1/2: feature rows as vec4 (DF, FB % 4 == 0)
layout(constant_id = 8) const bool WVEC4 = true;  // N % 4 == 0
#include "act.glsl"

layout(std430, binding = 2) readonly buffer W_ { float W[]; };   // [K][N]
#ifdef WEIGHTS_UNIFORM
// point_mlp_ubo.comp: the weights as a uniform buffer, K * N / 4 vec4s (WVEC4 only).
layout(constant_id = 9) const uint WVECS = 1;
layout(std140, binding = 3) uniform W4_ { vec4 W4[WVECS]; };
#else
layout(std430, binding = 3) readonly buffer W4_ { vec4 W4[]; };
#endif
layout(std430, binding = 4) readonly buffer Bias_ { float bias[]; };
layout(std430, binding = 5) writeonly buffer Out_ { float outv[]; };
layout(std430, binding = 6) readonly buffer Centre_ { float centre[]; };  // MODE 1: [S][3]
layout(std430, binding = 7) readonly buffer Index_ { int idx[]; };       // MODE 1: [S][NS]
layout(push_constant) uniform Push {
    uint M; uint N; uint K; uint NS; float slope;
    uint P; uint D; uint DF; uint FB; uint CF;
    uint blocks;  // invocations needed along x: row blocks, or groups (MAXPOOL)
    uint chunks;  // MAXPOOL: TM-row blocks per group
    uint WN;      // columns of the bound weights: N, or one block's (group_linear.cpp)
    uint n_base;  // the first output channel they hold
} p;

float acc[TM * TN];

void fma_row(float a[TM], uint k) {
    float w[TN];
    if (WVEC4) {
        [[unroll]] for (uint j = 0; j < TN / 4; ++j) {
            vec4 v = W4[(k * p.WN) / 4 + min(gl_WorkGroupID.y * TN / 4 + j, p.WN / 4 - 1)];
            w[4 * j] = v.x, w[4 * j + 1] = v.y, w[4 * j + 2] = v.z, w[4 * j + 3] = v.w;
        }
    } else {
        [[unroll]] for (uint j = 0; j < TN; ++j) w[j] = W[k * p.WN + min(gl_WorkGroupID.y * TN + j, p.WN - 1)];
    }
    [[unroll]] for (uint i = 0; i < TM; ++i)
        [[unroll]] for (uint j = 0; j < TN; ++j) acc[i * TN + j] = fma(a[i], w[j], acc[i * TN + j]);
}

// acc = A[rows] W for the TM rows m0 .. m0 + TM - 1 (rows past `mend` read row mend - 1).
void block(uint m0, uint mend) {
    [[unroll]] for (uint i = 0; i < TM * TN; ++i) acc[i] = 0.0;
    uint rows[TM];
    [[unroll]] for (uint i = 0; i < TM; ++i) rows[i] = min(m0 + i, mend - 1u);
    float a[TM];
    if (MODE == 0u) {
        for (uint k = 0; k < p.K; ++k) {
            if (AVEC4) {
                [[unroll]] for (uint i = 0; i < TM / 4; ++i) {
                    vec4 v = LOAD_A4((k * p.M + rows[4 * i]) / 4);  // rows[4i] is a multiple of 4 here
                    a[4 * i] = v.x, a[4 * i + 1] = v.y, a[4 * i + 2] = v.z, a[4 * i + 3] = v.w;
                }
            } else {
                [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = LOAD_A(k * p.M + rows[i]);
            }
            fma_row(a, k);
        }
        return;
    }
    // MODE 1 / 2 / 3: each row's source point, and for MODE 1 its offset from the centre.
    uint q[TM];
    vec3 xyz[TM];
    [[unroll]] for (uint i = 0; i < TM; ++i) {
        if (MODE == 1u) {
            q[i] = min(uint(idx[rows[i]]), p.P - 1u);  // in range whatever the indices hold
            uint c = 3u * (rows[i] / p.NS);
            xyz[i] = vec3(LOAD_A(q[i] * p.D) - centre[c], LOAD_A(q[i] * p.D + 1u) - centre[c + 1u],
                          LOAD_A(q[i] * p.D + 2u) - centre[c + 2u]);
        } else {
            q[i] = rows[i];
            const uint d = MODE == 3u ? p.D : 3u;
            xyz[i] = vec3(LOAD_A(d * q[i]), LOAD_A(d * q[i] + 1u), LOAD_A(d * q[i] + 2u));
        }
    }
    const uint kf = MODE == 2u ? 3u : 0u;  // first feature column of the row
    if (MODE == 2u)
        [[unroll]] for (uint c = 0; c < 3; ++c) {
            [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = xyz[i][c];
            fma_row(a, c);
        }
    if (FVEC4) {
        for (uint k = 0; k < p.CF; k += 4u) {
            vec4 f[TM];
            [[unroll]] for (uint i = 0; i < TM; ++i) f[i] = LOAD_F4((q[i] * p.DF + p.FB + k) / 4u);
            [[unroll]] for (uint c = 0; c < 4; ++c) {
                [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = f[i][c];
                fma_row(a, kf + k + c);
            }
        }
    } else {
        for (uint k = 0; k < p.CF; ++k) {
            [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = LOAD_F(q[i] * p.DF + p.FB + k);
            fma_row(a, kf + k);
        }
    }
    if (MODE == 1u || MODE == 3u)
        [[unroll]] for (uint c = 0; c < 3; ++c) {
            [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = xyz[i][c];
            fma_row(a, p.CF + c);
        }
}

void main() {
    // Spare invocations redo the last block and store nothing: no early return,
    // so every loop below has a uniform trip count (its counters stay uniform
    // and the weight loads with them).
    const uint t_all = gl_WorkGroupID.x * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    const bool live = t_all < p.blocks;
    const uint t = min(t_all, p.blocks - 1u);
    const uint n0 = gl_WorkGroupID.y * TN;  // within the bound weight columns
    const uint nb = p.n_base + n0;          // the output channel of column n0
    float b[TN];
    [[unroll]] for (uint j = 0; j < TN; ++j) b[j] = bias[min(nb + j, p.N - 1u)];
    if (!MAXPOOL) {
        const uint m0 = t * TM;
        block(m0, p.M);
        [[unroll]] for (uint j = 0; j < TN; ++j) {
            [[unroll]] for (uint i = 0; i < TM; ++i)
                if (live && n0 + j < p.WN && m0 + i < p.M) outv[(nb + j) * p.M + m0 + i] = apply_act(acc[i * TN + j] + b[j], ACT, p.slope);
        }
        return;
    }
    float mx[TN];
    [[unroll]] for (uint j = 0; j < TN; ++j) mx[j] = uintBitsToFloat(0xFF800000u);  // -inf
    const uint g0 = t * p.NS, gend = g0 + p.NS;
    for (uint c = 0; c < p.chunks; ++c) {
        block(g0 + c * TM, gend);
        // Rows past the group's end repeat its last row: harmless for a max.
        [[unroll]] for (uint i = 0; i < TM; ++i)
            [[unroll]] for (uint j = 0; j < TN; ++j) mx[j] = max(mx[j], apply_act(acc[i * TN + j] + b[j], ACT, p.slope));
    }
    [[unroll]] for (uint j = 0; j < TN; ++j)
        if (live && n0 + j < p.WN) outv[t * p.N + nb + j] = mx[j];
}
