#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
// chamfer_nn.comp's nearest-neighbour distances with the target rows passed
// between lanes by subgroupShuffle instead of a shared-memory tile: each lane
// loads one target row per round and every lane of its subgroup reads it from
// there. No shared memory, no barrier. Why: where a shared-memory load is a loop
// over the lanes (CPU drivers), reading the tile cost more than the distances.
// Same layout, outputs, NaN rule and target chunks as chamfer_nn.comp, Q
// queries per thread. The workgroup is whole subgroups (the host's choice), and
// every lane takes part in every shuffle, queries past the end included.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool WIDE = false;  // rows of 6 (xyz + normal), else 3
// Queries per thread (the workgroup's Q * L queries strided by L): each shuffled
// target row serves Q distances, where shuffles cost more than the arithmetic.
layout(constant_id = 2) const uint Q = 1;

layout(std430, binding = 0) readonly buffer A_ { float A[]; };
layout(std430, binding = 1) readonly buffer B_ { float B[]; };
layout(std430, binding = 2) buffer Mins_ { float mins[]; };
layout(push_constant) uniform Push { uint Na; uint Nb; uint groups_a; uint t_begin; uint t_chunk; } p;

const uint D = WIDE ? 6u : 3u;

// Row i of set A (this workgroup's set) or B; zeros past the end.
void load_row(bool from_a, uint i, uint n, out vec3 xyz, out vec3 nrm) {
    xyz = vec3(0.0);
    nrm = vec3(0.0);
    if (i >= n) return;
    uint b = i * D;
    if (from_a) {
        b += gl_WorkGroupID.y * p.Na * D;
        xyz = vec3(A[b], A[b + 1u], A[b + 2u]);
        if (WIDE) nrm = vec3(A[b + 3u], A[b + 4u], A[b + 5u]);
    } else {
        xyz = vec3(B[b], B[b + 1u], B[b + 2u]);
        if (WIDE) nrm = vec3(B[b + 3u], B[b + 4u], B[b + 5u]);
    }
}

void main() {
    const uint L = gl_WorkGroupSize.x, S = gl_SubgroupSize;
    const bool from_a = gl_WorkGroupID.x < p.groups_a;  // queries from A, targets from B
    const uint nq = from_a ? p.Na : p.Nb, n_all = from_a ? p.Nb : p.Na;
    const uint t_first = min(p.t_begin, n_all);
    const uint nt = min(p.t_chunk, n_all - t_first);  // targets of this chunk (uniform)
    const uint q0 = (from_a ? gl_WorkGroupID.x : gl_WorkGroupID.x - p.groups_a) * L * Q + gl_LocalInvocationID.x;
    vec3 qp[Q], qn[Q];
    float best[Q];
    bool nan[Q];
    [[unroll]] for (uint k = 0u; k < Q; ++k) {
        load_row(from_a, q0 + k * L, nq, qp[k], qn[k]);
        best[k] = 1.0 / 0.0;
        nan[k] = false;
    }
    for (uint t0 = 0u; t0 < nt; t0 += S) {
        vec3 tp, tn;
        load_row(!from_a, t_first + t0 + gl_SubgroupInvocationID, t_first + nt, tp, tn);
        const uint rows = min(S, nt - t0);
        for (uint j = 0u; j < rows; ++j) {
            const vec3 sp = subgroupShuffle(tp, j);
            const vec3 sn = WIDE ? subgroupShuffle(tn, j) : vec3(0.0);
            [[unroll]] for (uint k = 0u; k < Q; ++k) {
                vec3 e = qp[k] - sp;
                float d = dot(e, e);
                if (WIDE) {
                    vec3 f = qn[k] - sn;
                    d += dot(f, f);
                }
                nan[k] = nan[k] || isnan(d);
                best[k] = min(best[k], d);
            }
        }
    }
    // A NaN anywhere makes the distance NaN rather than silently ignored.
    const uint base = gl_WorkGroupID.y * (p.Na + p.Nb) + (from_a ? 0u : p.Na);
    if (nt == 0u) return;  // no targets left in this chunk for this set
    [[unroll]] for (uint k = 0u; k < Q; ++k) {
        const uint q = q0 + k * L;
        if (q >= nq) break;
        if (nan[k]) {
            mins[base + q] = 0.0 / 0.0;
        } else if (p.t_begin == 0u) {
            mins[base + q] = best[k];
        } else {
            const float old = mins[base + q];
            mins[base + q] = isnan(old) ? old : min(old, best[k]);
        }
    }
}
