// Body of point_mlp.comp (texel-buffer reads of the activations and the cloud),
// point_mlp_shfl.comp (the same with the weights shared by subgroup shuffles),
// point_mlp_ubo.comp (the weights in a uniform buffer) and point_mlp_ssbo.comp
// (storage buffers, for tensors beyond the device's texel-buffer limit); which
// one runs: group_linear.cpp. They declare bindings 0, 1, 6 - 11 and LOAD_A, LOAD_A4,
// LOAD_C, LOAD_I, LOAD_F, LOAD_F4, LOAD_H4, LOAD_HB4 (point_mlp_shfl.comp also
// binding 2 and LOAD_W, LOAD_WV4).
//
// One PointNet++ MLP layer (1x1 conv, BatchNorm folded, act): out = act(A W + b)
// with W stored [K][N] (input-major, so 4 output channels are one vec4), and the
// grouping fused into the input or the neighbour max into the output:
// MODE 0: A is the previous layer's output, channel-major [K][M] (4 rows = one vec4),
//   or with XPM point-major [M][K] (4 channels = one vec4; AVEC4 then means K % 4 == 0).
// MODE 1 (gather): row m = (centre m / NS, slot) is [features of q, xyz of q - centre],
//   q = idx[m], read straight from the cloud (SPEC 2: features first).
// MODE 2 (group all): row m is [xyz of m, features of m] (xyz first, not centred).
// MODE 3 (per point): row m is [features of m, xyz of m] (MODE 1's columns for the
//   point itself, not centred: sa_gather.comp subtracts the centre's share).
// MAXPOOL: out[g][n] = max over the NS rows of group g (point-major [M / NS][N]);
//   else out is channel-major [N][M], or point-major [M][N] with PMOUT: the next
//   layer's MODE 0 input (XPM when point-major).
// HIDDEN (MODE 1 only): A is a first layer computed 4 channels at a time in
//   registers and never stored (K % 4 == 0; W0 [CF + 3][K], its xyz rows from CF):
//   1: act(row W0 + b0) of the gathered row (CF <= 4): a narrow first layer
//      (6 inputs) was bound by the stores of its output (point_encoder.cpp);
//   2: act(U[q] - W0's xyz rows . centre), U (binding 0) = the first layer per
//      source point, point-major [P][K]: sa_gather's arithmetic, unstored.
// PMOUT: a plain output point-major [M][N] (4 channels a store): HIDDEN 2's U, and
//   the rows between a scale's layers (any MODE, with or without PAD).
// PAD: ball padding (SPEC 2 fills a ball's free slots with its first index, so such
//   a row repeats row 0's input and output) is work skipped: a row past a group's
//   first whose index (binding 7, [M / NS][NS]) equals the first's is left out of the
//   max, and a plain output may leave it unwritten. point_mlp_shfl.comp (it has
//   subgroup votes and shuffles; the others compute every row) skips the chunks
//   past a ball's last real row: the subgroup's balls pool their chunks (Pool; a
//   plain output with POOL, a max where that takes fewer steps), or, for a plain
//   output on a GPU, a subgroup skips the row blocks (row_block) that are all
//   padding. The max after such an output takes PAD as well.
// Register blocking and no shared memory: an invocation owns TM rows x TN channels
// (MAXPOOL: all rows of one group, TM at a time) and per 4 input channels does
// 4 x TM x TN fmas (fma_rows). The channel block is uniform in a workgroup (CBLOCK), so
// every lane reads the same weights: on GPUs a broadcast; on lavapipe a loop over
// the lanes from a storage buffer, a gather from a uniform buffer whose offset
// depends on the loop (Mesa 22.3 takes only constant offsets as uniform), and
// one gather per subgroup-size weights (per 4 x subgroup-size where N % 4 == 0)
// when shared by shuffles.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint TM = 4;   // rows per block, multiple of 4
layout(constant_id = 2) const uint TN = 16;  // channels per invocation, multiple of 4
layout(constant_id = 3) const uint MODE = 0;
layout(constant_id = 4) const bool MAXPOOL = false;
layout(constant_id = 5) const uint ACT = 0;  // act.glsl code
layout(constant_id = 6) const bool AVEC4 = true;  // MODE 0: x as vec4 (M, and NS when MAXPOOL, % 4 == 0; XPM: K % 4 == 0)
layout(constant_id = 7) const bool FVEC4 = true;  // MODE 1/2: feature rows as vec4 (DF, FB % 4 == 0)
layout(constant_id = 8) const bool WVEC4 = true;  // N % 4 == 0
// !MAXPOOL, M % 4 == 0: 4 rows a store. A CPU driver stores lane by lane, a branch
// each: 4x fewer stores took the paper's sa1 widest-scale middle layer from 57 to 37 ms.
layout(constant_id = 11) const bool OVEC4 = true;
layout(constant_id = 12) const uint HIDDEN = 0;  // MODE 1: A from a layer in registers (LOAD_H4, LOAD_HB4)
layout(constant_id = 13) const bool PMOUT = false;
// The channel block along x and the row block along y (group_linear.cpp says why), or the reverse.
layout(constant_id = 14) const bool CB_FIRST = false;
layout(constant_id = 15) const bool PAD = false;
layout(constant_id = 16) const bool XPM = false;
// PAD, plain output, vote shader: one invocation per ball, the subgroup's chunks
// pooled (main), instead of one per row block (row_block).
layout(constant_id = 17) const bool POOL = false;
// MAXPOOL, vote shader: PARTS neighbouring lanes of a subgroup share a group, lane q
// taking its chunks q, q + PARTS, ...; their maxima meet by xor shuffles (a power of
// two <= SG). More lanes for a GPU when a layer has few groups (group_linear.cpp).
layout(constant_id = 18) const uint PARTS = 1;
#ifdef SUBGROUP_VOTE
#define ANY_LANE(x) subgroupAny(x)
const bool SKIP_BLOCKS = PAD;
#else
#define ANY_LANE(x) true
const bool SKIP_BLOCKS = false;  // without a vote every lane computes its block
#endif
#define CBLOCK (CB_FIRST ? gl_WorkGroupID.x : gl_WorkGroupID.y)
#define RBLOCK (CB_FIRST ? gl_WorkGroupID.y : gl_WorkGroupID.x)
#include "act.glsl"

#ifndef WEIGHTS_SHUFFLE
layout(std430, binding = 2) readonly buffer W_ { float W[]; };   // [K][N]
#endif
#ifdef WEIGHTS_UNIFORM
// point_mlp_ubo.comp: the weights as a uniform buffer, K * N / 4 vec4s (WVEC4 only).
layout(constant_id = 9) const uint WVECS = 1;
layout(std140, binding = 3) uniform W4_ { vec4 W4[WVECS]; };
#else
layout(std430, binding = 3) readonly buffer W4_ { vec4 W4[]; };
#endif
layout(std430, binding = 4) readonly buffer Bias_ { float bias[]; };
layout(std430, binding = 5) writeonly buffer Out_ { vec4 outv[]; };
layout(push_constant) uniform Push {
    uint M; uint N; uint K; uint NS; float slope;
    uint P; uint D; uint DF; uint FB; uint CF;
    uint blocks;  // invocations needed along x: row blocks, or groups (MAXPOOL)
    uint chunks;  // MAXPOOL: TM-row blocks per group
} p;

float acc[TM * TN];

#ifdef WEIGHTS_SHUFFLE
layout(constant_id = 10) const uint SG = 8;  // the device's subgroup size
const uint WR = (TN + SG - 1u) / SG;         // weights each lane loads per input channel
const uint WR4 = (TN / 4u + SG - 1u) / SG;   // the same in vec4s (WVEC4: binding 2 is RGBA32F)
const uint HR = (7u + SG - 1u) / SG;         // HIDDEN 1: W0 rows each lane fetches per 4 channels
#endif

// acc += the products of the 4 input channels k0 .. k0 + 3 (a[i][u]: row i, channel
// k0 + u; channels past K come with a = 0 and a clamped weight row). Each
// accumulator takes its 4 products in a row: a CPU driver masks every store to a
// value a loop carries (load, blend, store), so it pays that once per 4 products.
// (The rows are vec4s: an array parameter sized by a spec-constant expression such
// as 4 * TM came out wrong through glslang and Mesa 22.3.)
void fma_rows(vec4 a[TM], uint k0) {
    float w[4 * TN];  // weight rows k0 .. k0 + 3 (clamped to K - 1), the block's TN columns
    [[unroll]] for (uint u = 0; u < 4; ++u) {
        const uint k = min(k0 + u, p.K - 1u);
#ifdef WEIGHTS_SHUFFLE
        // Lane l loads columns l, l + SG, ...; all lanes take them by shuffles at
        // constant lane indices: one gather per SG weights instead of one per weight.
        // With WVEC4, lane l loads the vec4 of columns 4l .. 4l + 3, ...: one fetch
        // per 4 SG weights. A CPU driver's texel fetch is a call, and the weight
        // fetches were most of a big layer's calls.
        if (WVEC4) {
            vec4 wl4[WR4];
            [[unroll]] for (uint r = 0; r < WR4; ++r)
                wl4[r] = LOAD_WV4((k * p.N) / 4u + min(CBLOCK * TN / 4u + min(r * SG + gl_SubgroupInvocationID, TN / 4u - 1u),
                                                      p.N / 4u - 1u));
            [[unroll]] for (uint j = 0; j < TN; ++j) w[u * TN + j] = subgroupShuffle(wl4[j / 4u / SG][j % 4u], (j / 4u) % SG);
        } else {
            float wl[WR];
            [[unroll]] for (uint r = 0; r < WR; ++r)
                wl[r] = LOAD_W(k * p.N + min(CBLOCK * TN + min(r * SG + gl_SubgroupInvocationID, TN - 1u), p.N - 1u));
            [[unroll]] for (uint j = 0; j < TN; ++j) w[u * TN + j] = subgroupShuffle(wl[j / SG], j % SG);
        }
#else
        if (WVEC4) {
            [[unroll]] for (uint j = 0; j < TN / 4; ++j) {
                vec4 v = W4[(k * p.N) / 4 + min(CBLOCK * TN / 4 + j, p.N / 4 - 1)];
                [[unroll]] for (uint c = 0; c < 4; ++c) w[u * TN + 4 * j + c] = v[c];
            }
        } else {
            [[unroll]] for (uint j = 0; j < TN; ++j) w[u * TN + j] = W[k * p.N + min(CBLOCK * TN + j, p.N - 1)];
        }
#endif
    }
    [[unroll]] for (uint i = 0; i < TM; ++i)
        [[unroll]] for (uint j = 0; j < TN; ++j) {
            float s = acc[i * TN + j];
            [[unroll]] for (uint u = 0; u < 4; ++u) s = fma(a[i][u], w[u * TN + j], s);
            acc[i * TN + j] = s;
        }
}

// acc = A[rows] W for the TM rows m0 .. m0 + TM - 1 (rows past `mend` read row mend - 1).
// Two fma_rows calls, not seven: MODE 0's loop, and one loop of 4-channel steps for
// the other modes. Lavapipe runs NIR's passes over every inlined copy of a call before
// it drops those a specialization leaves dead, in every process that creates the
// pipeline (docs/performance.md, "Pipeline compile time"). MODE 0 keeps its own
// loop: in the shared one the max layers ran about 3 % slower.
void block(uint m0, uint mend) {
    [[unroll]] for (uint i = 0; i < TM * TN; ++i) acc[i] = 0.0;
    uint rows[TM];
    [[unroll]] for (uint i = 0; i < TM; ++i) rows[i] = min(m0 + i, mend - 1u);
    vec4 a[TM];
    if (MODE == 0u) {
        for (uint k0 = 0; k0 < p.K; k0 += 4u) {
            [[unroll]] for (uint u = 0; u < 4; ++u) {
                const uint k = min(k0 + u, p.K - 1u);
                const bool live = k0 + u < p.K;
                if (XPM && AVEC4) {  // a row's 4 channels at once
                    if (u == 0u) [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = LOAD_A4((rows[i] * p.K + k0) / 4u);
                } else if (XPM) {
                    [[unroll]] for (uint i = 0; i < TM; ++i) a[i][u] = live ? LOAD_A(rows[i] * p.K + k) : 0.0;
                } else if (AVEC4) {
                    [[unroll]] for (uint i = 0; i < TM / 4; ++i) {
                        vec4 v = live ? LOAD_A4((k * p.M + rows[4 * i]) / 4) : vec4(0.0);  // rows[4i] is a multiple of 4 here
                        [[unroll]] for (uint c = 0; c < 4; ++c) a[4 * i + c][u] = v[c];
                    }
                } else {
                    [[unroll]] for (uint i = 0; i < TM; ++i) a[i][u] = live ? LOAD_A(k * p.M + rows[i]) : 0.0;
                }
            }
            fma_rows(a, k0);
        }
        return;
    }
    // MODE 1 / 2 / 3: each row's source point, and for MODE 1 its offset from the centre.
    uint q[TM];
    vec3 xyz[TM];
    vec4 f[TM];  // HIDDEN 1: the row's features (CF <= 4; zeros past CF), in registers through every step
    [[unroll]] for (uint i = 0; i < TM; ++i) {
        if (MODE == 1u) {
            q[i] = min(uint(LOAD_I(rows[i])), p.P - 1u);  // in range whatever the indices hold
            uint c = 3u * (rows[i] / p.NS);
            if (HIDDEN == 2u)  // the centre itself
                xyz[i] = vec3(LOAD_C(c), LOAD_C(c + 1u), LOAD_C(c + 2u));
            else
                xyz[i] = vec3(LOAD_A(q[i] * p.D) - LOAD_C(c), LOAD_A(q[i] * p.D + 1u) - LOAD_C(c + 1u),
                              LOAD_A(q[i] * p.D + 2u) - LOAD_C(c + 2u));
        } else {
            q[i] = rows[i];
            const uint d = MODE == 3u ? p.D : 3u;
            xyz[i] = vec3(LOAD_A(d * q[i]), LOAD_A(d * q[i] + 1u), LOAD_A(d * q[i] + 2u));
        }
    }
    if (HIDDEN == 1u)
        [[unroll]] for (uint i = 0; i < TM; ++i)
            [[unroll]] for (uint u = 0; u < 4; ++u)
                f[i][u] = u < p.CF ? LOAD_F(q[i] * p.DF + p.FB + min(u, max(p.CF, 1u) - 1u)) : 0.0;
    // Steps of 4 input channels: K of them for HIDDEN; else the features' and one
    // of the 3 xyz columns whose last channel is 0 (first for MODE 2, last for MODE 1 and 3).
    const uint steps = HIDDEN != 0u ? (p.K + 3u) / 4u : (p.CF + 3u) / 4u + 1u;
    const uint xyz_step = MODE == 2u ? 0u : steps - 1u;
    const uint kf = MODE == 2u ? 3u : 0u;  // first feature column of the row
    for (uint s = 0; s < steps; ++s) {
        uint k0 = 4u * s;  // the step's first weight row
        if (HIDDEN == 2u) {
            vec4 wx[3];
            [[unroll]] for (uint j = 0; j < 3; ++j) wx[j] = LOAD_H4(((p.CF + j) * p.K + k0) / 4u);
            [[unroll]] for (uint i = 0; i < TM; ++i) {
                const vec4 h = LOAD_A4((q[i] * p.K + k0) / 4u) - (xyz[i].x * wx[0] + xyz[i].y * wx[1] + xyz[i].z * wx[2]);
                [[unroll]] for (uint u = 0; u < 4; ++u) a[i][u] = apply_act(h[u], ACT, p.slope);
            }
        } else if (HIDDEN == 1u) {
            vec4 wf[4], wx[3];  // W0 rows of the features and of xyz, channels k0 .. k0 + 3
#ifdef WEIGHTS_SHUFFLE
            // Lane l fetches row l of the 7 (wf, then wx) and the lanes share them by
            // shuffles: a fetch at a uniform index is still a gather on a CPU driver
            // (1-1.5 % of the point MLPs' time, docs/performance.md "W0 rows by shuffles").
            vec4 hl[HR];
            [[unroll]] for (uint r = 0; r < HR; ++r) {
                const uint item = min(r * SG + gl_SubgroupInvocationID, 6u);
                const uint row = min(item < 4u ? item : p.CF + item - 4u, p.CF + 2u);
                const vec4 h = LOAD_H4((row * p.K + k0) / 4u);
                hl[r] = item < 4u && item >= p.CF ? vec4(0.0) : h;
            }
            [[unroll]] for (uint u = 0; u < 4; ++u) wf[u] = subgroupShuffle(hl[u / SG], u % SG);
            [[unroll]] for (uint j = 0; j < 3; ++j) wx[j] = subgroupShuffle(hl[(4u + j) / SG], (4u + j) % SG);
#else
            [[unroll]] for (uint u = 0; u < 4; ++u) wf[u] = u < p.CF ? LOAD_H4((u * p.K + k0) / 4u) : vec4(0.0);
            [[unroll]] for (uint j = 0; j < 3; ++j) wx[j] = LOAD_H4(((p.CF + j) * p.K + k0) / 4u);
#endif
            const vec4 b0 = LOAD_HB4(k0 / 4u);
            [[unroll]] for (uint i = 0; i < TM; ++i) {
                vec4 h = b0;
                [[unroll]] for (uint u = 0; u < 4; ++u) h = fma(vec4(f[i][u]), wf[u], h);
                [[unroll]] for (uint j = 0; j < 3; ++j) h = fma(vec4(xyz[i][j]), wx[j], h);
                [[unroll]] for (uint u = 0; u < 4; ++u) a[i][u] = apply_act(h[u], ACT, p.slope);
            }
        } else if (s == xyz_step) {
            [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = vec4(xyz[i], 0.0);
            k0 = MODE == 2u ? 0u : p.CF;
        } else {
            const uint k = 4u * (MODE == 2u ? s - 1u : s);  // the step's first feature column
            if (FVEC4) {  // CF % 4 == 0 here
                [[unroll]] for (uint i = 0; i < TM; ++i) a[i] = LOAD_F4((q[i] * p.DF + p.FB + k) / 4u);
            } else {
                [[unroll]] for (uint u = 0; u < 4; ++u) {
                    const bool live = k + u < p.CF;
                    const uint c = min(k + u, p.CF - 1u);
                    [[unroll]] for (uint i = 0; i < TM; ++i) a[i][u] = live ? LOAD_F(q[i] * p.DF + p.FB + c) : 0.0;
                }
            }
            k0 = kf + k;
        }
        fma_rows(a, k0);
    }
}

// Row r (< M) repeats its group's first row's index (PAD).
bool padding_row(uint r) {
    const uint r0 = r / p.NS * p.NS;
    return r != r0 && LOAD_I(r) == LOAD_I(r0);
}

// The row block invocation t computes. PAD, plain output (the vote shader on a
// GPU): lane i of a subgroup takes block b of group chunk * SG + i, so a subgroup
// skips block b where none of its SG balls has a real row there (a block of 8 rows
// where rows in order would need a subgroup's 8 blocks, 64 rows, all padding).
// Groups that do not fill a subgroup keep the rows in order. A permutation: any
// subgroup layout stays exact.
uint row_block(uint t) {
#ifdef SUBGROUP_VOTE
    const uint B = p.NS / TM, full = p.M / p.NS / SG * SG * B;  // blocks per group; blocks of whole-subgroup chunks
    if (PAD && p.NS % TM == 0 && t < full) {
        const uint r = t % (SG * B);
        return ((t / (SG * B)) * SG + r % SG) * B + r / SG;
    }
#endif
    return t;
}

float b[TN];  // the block's biases

// Stores the plain output of rows m0 .. m0 + TM - 1 below mend (acc + b, act).
void store_rows(uint m0, uint mend, bool live, uint n0) {
    if (PMOUT) {
        [[unroll]] for (uint i = 0; i < TM; ++i)
            [[unroll]] for (uint j = 0; j < TN; j += 4u) {
                vec4 v;
                [[unroll]] for (uint c = 0; c < 4; ++c) v[c] = apply_act(acc[i * TN + j + c] + b[j + c], ACT, p.slope);
                const uint e = (m0 + i) * p.N + n0 + j;
                if (!live || m0 + i >= mend) continue;
                if (WVEC4) {
                    if (n0 + j < p.N) outv[e / 4u] = v;
                } else {
                    [[unroll]] for (uint c = 0; c < 4; ++c)
                        if (n0 + j + c < p.N) outv[(e + c) / 4u][(e + c) % 4u] = v[c];
                }
            }
        return;
    }
    [[unroll]] for (uint j = 0; j < TN; ++j) {
        if (OVEC4) {  // m0 and mend are multiples of 4 here
            [[unroll]] for (uint i = 0; i < TM; i += 4u) {
                vec4 v;
                [[unroll]] for (uint c = 0; c < 4; ++c) v[c] = apply_act(acc[(i + c) * TN + j] + b[j], ACT, p.slope);
                if (live && n0 + j < p.N && m0 + i < mend) outv[((n0 + j) * p.M + m0 + i) / 4u] = v;
            }
        } else {
            [[unroll]] for (uint i = 0; i < TM; ++i) {
                const uint e = (n0 + j) * p.M + m0 + i;
                if (live && n0 + j < p.N && m0 + i < mend) outv[e / 4u][e % 4u] = apply_act(acc[i * TN + j] + b[j], ACT, p.slope);
            }
        }
    }
}

#ifdef SUBGROUP_VOTE
// PAD: a ball needs its chunks of TM rows up to its last real row (padding is the
// tail SPEC 2's ball query leaves; rows are checked one by one all the same). One
// lane per ball makes a subgroup take as many steps as its longest ball; pooled,
// each step gives the next SG chunks of its balls' chunks to its SG lanes.
struct Pool {
    uint mine;    // this lane's ball's chunks (0 for a spare invocation)
    uint before;  // the chunks of the lanes below this one
    uint total;   // the subgroup's chunks
    uint most;    // the most chunks of one ball
};

Pool pool_of(uint g0, bool live) {
    const int first = LOAD_I(g0);
    uint used = 1u;
    for (uint j = 1u; j < p.NS; ++j)
        if (LOAD_I(g0 + j) != first) used = j + 1u;
    Pool pl;
    pl.mine = live ? (used + TM - 1u) / TM : 0u;
    pl.before = pl.total = pl.most = 0u;
    for (uint l = 0u; l < SG; ++l) {
        const uint c = subgroupShuffle(pl.mine, l);
        pl.before += l < gl_SubgroupInvocationID ? c : 0u;
        pl.total += c;
        pl.most = max(pl.most, c);
    }
    return pl;
}

// This lane's chunk in step s of the pool (t: the lane's own ball): (the lane that
// owns the chunk's ball, that ball's first row, the chunk's first row). Past the
// pool: owner SG and lane SG - 1's first chunk, to compute and not use.
uvec3 pool_chunk(Pool pl, uint s, uint t) {
    const uint item = s + gl_SubgroupInvocationID;
    uint owner = SG, chunk = 0u;
    for (uint l = 0u; l < SG; ++l) {
        const uint bl = subgroupShuffle(pl.before, l), ml = subgroupShuffle(pl.mine, l);
        if (item >= bl && item < bl + ml) owner = l, chunk = item - bl;
    }
    const uint h0 = subgroupShuffle(t, min(owner, SG - 1u)) * p.NS;
    return uvec3(owner, h0, h0 + chunk * TM);
}
#endif

void main() {
    // Spare invocations redo the last block and store nothing: no early return
    // (but PAD's, taken by whole subgroups), so every loop below has a uniform trip
    // count (its counters stay uniform and the weight loads with them).
    const uint t_all = RBLOCK * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    const bool live = t_all < p.blocks;
    const uint t = min(t_all, p.blocks - 1u);
    const uint n0 = CBLOCK * TN;
    [[unroll]] for (uint j = 0; j < TN; ++j) b[j] = bias[min(n0 + j, p.N - 1u)];
#ifdef SUBGROUP_VOTE
    if (POOL) {  // PAD, a plain output, one invocation per ball (group_linear.cpp: CPU devices)
        const Pool pl = pool_of(t * p.NS, live);
        for (uint s = 0u; s < pl.total; s += SG) {  // uniform: the subgroup's total
            const uvec3 c = pool_chunk(pl, s, t);
            block(c.z, c.y + p.NS);
            store_rows(c.z, c.y + p.NS, c.x < SG, n0);
        }
        return;
    }
#endif
    if (!MAXPOOL) {
        const uint m0 = row_block(t) * TM;
        if (SKIP_BLOCKS) {  // a subgroup-uniform return: the shuffles below see every lane
            bool need = false;
            [[unroll]] for (uint i = 0; i < TM; ++i) need = need || (m0 + i < p.M && !padding_row(m0 + i));
            if (!ANY_LANE(live && need)) return;
        }
        block(m0, p.M);
        store_rows(m0, p.M, live, n0);
        return;
    }
    float mx[TN];
    [[unroll]] for (uint j = 0; j < TN; ++j) mx[j] = uintBitsToFloat(0xFF800000u);  // -inf
    uint grp = t, part = 0u;
    bool store = live;
#ifdef SUBGROUP_VOTE
    if (PARTS > 1u) {  // by lane, so that a group's PARTS lanes are neighbours in one subgroup
        // Full subgroups of SG lanes, as the weight shuffles already need (group_linear.cpp).
        const uint ta = RBLOCK * gl_WorkGroupSize.x + gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID;
        store = ta < p.blocks && ta % PARTS == 0u;
        grp = min(ta, p.blocks - 1u) / PARTS;
        part = ta % PARTS;
    }
#endif
    const uint g0 = grp * p.NS, gend = g0 + p.NS;
#ifdef SUBGROUP_VOTE
    // Pooled where that takes less time than one lane per ball; a chunk's max
    // reaches the lane that owns its ball by SG rounds of TN shuffles (max is
    // order-free: the same values either way). A step costs TM K multiply-adds a
    // channel, the rounds about 3 SG operations more: much for narrow layers on
    // wide subgroups (K = 32, SG = 32: a third more).
    const Pool pl = PAD ? pool_of(g0, live) : Pool(0u, 0u, 0u, 0u);
    const bool pooled = PARTS == 1u && (pl.total + SG - 1u) / SG * (TM * p.K + 3u * SG) < pl.most * TM * p.K;  // subgroup-uniform
    const uint steps = pooled ? (pl.total + SG - 1u) / SG : (p.chunks + PARTS - 1u) / PARTS;
#else
    const uint steps = p.chunks;
#endif
    // One loop and one block() call for both forms: NIR's passes run over every
    // inlined copy of block() (its comment says why that matters).
    for (uint s = 0u; s < steps; ++s) {
        // A lane past its share (PARTS > 1) redoes the last chunk and keeps none of it.
        const bool beyond = s * PARTS + part >= p.chunks;
        uint m0 = g0 + min(s * PARTS + part, p.chunks - 1u) * TM, mend = gend, owner = 0u;
        bool pad[TM];
#ifdef SUBGROUP_VOTE
        if (pooled) {
            const uvec3 c = pool_chunk(pl, s * SG, t);
            m0 = c.z, mend = c.y + p.NS, owner = c.x;
            [[unroll]] for (uint i = 0; i < TM; ++i) pad[i] = c.x == SG || padding_row(min(c.z + i, c.y + p.NS - 1u));
        } else
#endif
        {
            [[unroll]] for (uint i = 0; i < TM; ++i) pad[i] = beyond;
            if (PAD) {  // padding rows may hold anything (PAD's plain output): left out, never used
                bool need = false;
                [[unroll]] for (uint i = 0; i < TM; ++i) {
                    pad[i] = beyond || padding_row(min(m0 + i, gend - 1u));
                    need = need || !pad[i];
                }
                if (!ANY_LANE(need)) continue;  // subgroup-uniform, as the return above
            }
        }
        block(m0, mend);
        // Rows past the group's end repeat its last row: harmless for a max.
        float cm[TN];
        [[unroll]] for (uint j = 0; j < TN; ++j) {
            cm[j] = uintBitsToFloat(0xFF800000u);
            [[unroll]] for (uint i = 0; i < TM; ++i)
                if (!pad[i]) cm[j] = max(cm[j], apply_act(acc[i * TN + j] + b[j], ACT, p.slope));
        }
#ifdef SUBGROUP_VOTE
        if (pooled) {
            for (uint l = 0u; l < SG; ++l) {
                const bool to_me = subgroupShuffle(owner, l) == gl_SubgroupInvocationID;
                [[unroll]] for (uint j = 0; j < TN; ++j) {
                    const float v = subgroupShuffle(cm[j], l);
                    if (to_me) mx[j] = max(mx[j], v);
                }
            }
            continue;
        }
#endif
        [[unroll]] for (uint j = 0; j < TN; ++j) mx[j] = max(mx[j], cm[j]);
    }
#ifdef SUBGROUP_VOTE
    for (uint o = 1u; o < PARTS; o <<= 1u)  // max is order-free: the same value as one lane's loop
        [[unroll]] for (uint j = 0; j < TN; ++j) mx[j] = max(mx[j], subgroupShuffleXor(mx[j], o));
#endif
    [[unroll]] for (uint j = 0; j < TN; ++j)
        if (store && n0 + j < p.N) outv[(grp * p.N + n0 + j) / 4u][(grp * p.N + n0 + j) % 4u] = mx[j];
}
