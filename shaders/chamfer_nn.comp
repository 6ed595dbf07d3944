#version 450
// Nearest-neighbour squared distances for the Chamfer distance, both directions in
// one dispatch: workgroups [0, groups_a) query rows of A against B, the rest rows
// of B against A; each thread holds two query rows (q, q + L) so that every tile
// value read from shared memory serves two distance evaluations. The target set
// streams through shared memory in tiles of L rows (one row loaded per thread),
// so each target row is read from memory once per workgroup.
// mins[r] = min_b ||a_r - b||^2 (r < Na), mins[Na + r] = min_a ||b_r - a||^2.
// Workgroup y = the set s of A (A holds sets of Na rows; B is shared): its A rows
// start at s * Na, its mins at s * (Na + Nb).
// One dispatch scans targets t_begin .. t_begin + t_chunk - 1 of the other set
// and, past the first chunk, keeps the smaller of its result and the stored one:
// the host splits long scans so that no invocation's loops run past a CPU
// driver's iteration limit (engine/ops/common.h).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool WIDE = false;  // rows of 6 (xyz + normal), else 3

layout(std430, binding = 0) readonly buffer A_ { float A[]; };
layout(std430, binding = 1) readonly buffer B_ { float B[]; };
layout(std430, binding = 2) buffer Mins_ { float mins[]; };
layout(push_constant) uniform Push { uint Na; uint Nb; uint groups_a; uint t_begin; uint t_chunk; } p;

const uint D = WIDE ? 6u : 3u;
shared vec3 tile_p[gl_WorkGroupSize.x];
shared vec3 tile_n[WIDE ? gl_WorkGroupSize.x : 1u];

vec3 row(uint set, uint i, uint c0) {
    uint b = i * D + c0;
    if (set == 0u) b += gl_WorkGroupID.y * p.Na * D;
    return set == 0u ? vec3(A[b], A[b + 1u], A[b + 2u]) : vec3(B[b], B[b + 1u], B[b + 2u]);
}

// This chunk's nearest distance, or NaN, merged with the earlier chunks' (at i).
float merge(bool first, bool nan, float best, uint i) {
    if (nan) return 0.0 / 0.0;
    if (first) return best;
    const float old = mins[i];
    return isnan(old) ? old : min(old, best);
}

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const bool from_a = gl_WorkGroupID.x < p.groups_a;
    const uint qset = from_a ? 0u : 1u;
    const uint nq = from_a ? p.Na : p.Nb;
    const uint n_all = from_a ? p.Nb : p.Na;
    const uint t_first = min(p.t_begin, n_all);
    const uint nt = min(p.t_chunk, n_all - t_first);  // targets of this chunk (uniform)
    const uint q = (from_a ? gl_WorkGroupID.x : gl_WorkGroupID.x - p.groups_a) * 2u * L + tid;
    const uint q2 = q + L;

    vec3 qp = q < nq ? row(qset, q, 0u) : vec3(0.0);
    vec3 qn = WIDE && q < nq ? row(qset, q, 3u) : vec3(0.0);
    vec3 qp2 = q2 < nq ? row(qset, q2, 0u) : vec3(0.0);
    vec3 qn2 = WIDE && q2 < nq ? row(qset, q2, 3u) : vec3(0.0);
    float best = 1.0 / 0.0, best2 = best;
    bool nan1 = false, nan2 = false;
    for (uint t0 = 0; t0 < nt; t0 += L) {
        uint rows = min(L, nt - t0);
        if (tid < rows) {
            tile_p[tid] = row(1u - qset, t_first + t0 + tid, 0u);
            if (WIDE) tile_n[tid] = row(1u - qset, t_first + t0 + tid, 3u);
        }
        barrier();
        for (uint j = 0; j < rows; ++j) {
            vec3 tp = tile_p[j];
            vec3 e = qp - tp, e2 = qp2 - tp;
            float d = dot(e, e), d2 = dot(e2, e2);
            if (WIDE) {
                vec3 tn = tile_n[j];
                vec3 f = qn - tn, f2 = qn2 - tn;
                d += dot(f, f);
                d2 += dot(f2, f2);
            }
            nan1 = nan1 || isnan(d);
            nan2 = nan2 || isnan(d2);
            best = min(best, d);
            best2 = min(best2, d2);
        }
        barrier();
    }
    // A NaN anywhere makes the distance NaN rather than silently ignored.
    const uint base = gl_WorkGroupID.y * (p.Na + p.Nb) + (from_a ? 0u : p.Na);
    if (nt == 0u) return;  // this set has no targets left in this chunk
    if (q < nq) mins[base + q] = merge(p.t_begin == 0u, nan1, best, base + q);
    if (q2 < nq) mins[base + q2] = merge(p.t_begin == 0u, nan2, best2, base + q2);
}
