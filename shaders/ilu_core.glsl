// The ILU head's state and one GRU iteration (SPEC 2), shared by ilu.comp (all
// N iterations in one dispatch) and ilu_step.comp (one iteration per dispatch,
// for the bench's per-iteration timestamps). One workgroup holds h, x and every
// gate in shared memory.
// Matvecs: the workgroup is R = L / G row groups of G lanes; a group computes one
// output row per round, its lanes reading consecutive weights, and the lanes'
// partial sums meet in shared memory (no subgroup size assumed) or, with
// ILU_SUBGROUP defined (ilu_subgroup.comp, ilu_step_subgroup.comp: the host picks
// them when the device has subgroup shuffles, G divides the subgroup size and L
// is whole subgroups), in registers by a butterfly of subgroup shuffles: no
// barrier per round, which on lavapipe is most of an iteration's cost.
// The x half of each gate ([h, x] input order) is the same in every iteration,
// so W[:, C:3C] x + b is computed once (ilu_init) and kept in gx.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint C = 16;   // hidden size
layout(constant_id = 2) const uint H = 16;   // head hidden size
layout(constant_id = 3) const uint G = 8;    // lanes per row group (divides L)
#include "act.glsl"

layout(std430, binding = 0) readonly buffer Ft_ { float ft[]; };
layout(std430, binding = 1) readonly buffer Fp_ { float fp[]; };
layout(std430, binding = 2) readonly buffer Iters_ { int iters; };
layout(std430, binding = 3) readonly buffer Wz_ { float Wz[]; };
layout(std430, binding = 4) readonly buffer Bz_ { float bz[]; };
layout(std430, binding = 5) readonly buffer Wr_ { float Wr[]; };
layout(std430, binding = 6) readonly buffer Br_ { float br[]; };
layout(std430, binding = 7) readonly buffer Wq_ { float Wq[]; };
layout(std430, binding = 8) readonly buffer Bq_ { float bq[]; };
layout(std430, binding = 9) readonly buffer W0_ { float W0[]; };
layout(std430, binding = 10) readonly buffer B0_ { float b0[]; };
layout(std430, binding = 11) readonly buffer W2_ { float W2[]; };
layout(std430, binding = 12) readonly buffer B2_ { float b2[]; };

const uint L = gl_WorkGroupSize.x;
const uint R = L / G;
const uint C3 = 3u * C;

shared float h[C];
shared float xv[2u * C];  // x = [F^p, ReLU(F^t)]
shared float gx[3u * C];  // x half + bias of z, r, q
shared float zr[2u * C];  // z, then r
shared float qv[C];
shared float hid[H];
shared float part[L];
shared float c[3];

#define tid gl_LocalInvocationID.x
// ilu.comp runs one workgroup per touch of a batch: its row of F^t (F^p is shared).
#define ft_row (gl_WorkGroupID.x * C)
#ifdef ILU_SUBGROUP
// A row group is G consecutive invocations of one subgroup (G divides its size).
#define lane (gl_SubgroupInvocationID % G)
#define grp ((gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID) / G)
#else
#define lane (gl_LocalInvocationID.x % G)
#define grp (gl_LocalInvocationID.x / G)
#endif

// Sum of the G lanes' partials of each row group, valid in lane 0. Called in
// uniform control flow; the second barrier frees `part` for the next round.
float group_sum(float s) {
    if (G == 1u) return s;  // one lane per row: nothing to combine, no barrier
#ifdef ILU_SUBGROUP
    for (uint o = G / 2u; o > 0u; o >>= 1u) s += subgroupShuffleXor(s, o);  // stays within the aligned group
    return s;
#endif
    part[tid] = s;
    barrier();
    float t = 0.0;
    if (lane == 0u)
        for (uint i = 0u; i < G; ++i) t += part[tid + i];
    barrier();
    return t;
}

// x from F^t and F^p (every dispatch needs it; cheap).
void ilu_load_x() {
    for (uint i = tid; i < C; i += L) {
        xv[i] = fp[i];
        xv[C + i] = max(ft[ft_row + i], 0.0);
    }
}

// h_0 = tanh(F^t), c = 0 and the x half of the gates.
void ilu_init() {
    ilu_load_x();
    for (uint i = tid; i < C; i += L) h[i] = apply_act(ft[ft_row + i], ACT_TANH, 0.0);
    if (tid < 3u) c[tid] = 0.0;
    barrier();

    for (uint base = 0u; base < C3; base += R) {
        uint j = base + grp, row = j % C;
        float s = 0.0;
        if (j < C3) {
            if (j < C) for (uint k = lane; k < 2u * C; k += G) s = fma(Wz[row * C3 + C + k], xv[k], s);
            else if (j < 2u * C) for (uint k = lane; k < 2u * C; k += G) s = fma(Wr[row * C3 + C + k], xv[k], s);
            else for (uint k = lane; k < 2u * C; k += G) s = fma(Wq[row * C3 + C + k], xv[k], s);
        }
        s = group_sum(s);
        if (lane == 0u && j < C3) gx[j] = s + (j < C ? bz[row] : j < 2u * C ? br[row] : bq[row]);
    }
    barrier();
}

// One GRU update of h and c += head(h). Uniform control flow; ends with a barrier.
void ilu_iteration() {
    // z = sigmoid(Lz([h, x])), r = sigmoid(Lr([h, x]))
    for (uint base = 0u; base < 2u * C; base += R) {
        uint j = base + grp, row = j % C;
        float s = 0.0;
        if (j < C) for (uint k = lane; k < C; k += G) s = fma(Wz[row * C3 + k], h[k], s);
        else if (j < 2u * C) for (uint k = lane; k < C; k += G) s = fma(Wr[row * C3 + k], h[k], s);
        s = group_sum(s);
        if (lane == 0u && j < 2u * C) zr[j] = apply_act(s + gx[j], ACT_SIGMOID, 0.0);
    }
    barrier();
    // q = tanh(Lq([r * h, x]))
    for (uint base = 0u; base < C; base += R) {
        uint row = base + grp;
        float s = 0.0;
        if (row < C) for (uint k = lane; k < C; k += G) s = fma(Wq[row * C3 + k], zr[C + k] * h[k], s);
        s = group_sum(s);
        if (lane == 0u && row < C) qv[row] = apply_act(s + gx[2u * C + row], ACT_TANH, 0.0);
    }
    barrier();
    for (uint i = tid; i < C; i += L) h[i] = (1.0 - zr[i]) * h[i] + zr[i] * qv[i];
    barrier();
    // c += Linear(H, 3)(ReLU(Linear(C, H)(h)))
    for (uint base = 0u; base < H; base += R) {
        uint row = base + grp;
        float s = 0.0;
        if (row < H) for (uint k = lane; k < C; k += G) s = fma(W0[row * C + k], h[k], s);
        s = group_sum(s);
        if (lane == 0u && row < H) hid[row] = max(s + b0[row], 0.0);
    }
    barrier();
    for (uint base = 0u; base < 3u; base += R) {
        uint row = base + grp;
        float s = 0.0;
        if (row < 3u) for (uint k = lane; k < H; k += G) s = fma(W2[row * H + k], hid[k], s);
        s = group_sum(s);
        if (lane == 0u && row < 3u) c[row] += s + b2[row];
    }
    barrier();
}
