// Body of fps.comp and fps_subgroup.comp.
// Farthest point sampling (SPEC 2), one workgroup for the whole cloud.
// Start at index 0; each step keeps, per point, the minimum squared distance
// to the chosen set and picks the largest, lowest index on a tie. Each thread
// owns points tid, tid + L, ...; a step is one pass over them (update the
// minimum, keep the thread's best) and a reduction of (distance, index) pairs:
// a shared-memory tree with log2(L) + 1 barriers (fps.comp), or, with
// SUBGROUP_REDUCE (fps_subgroup.comp), each subgroup's best by subgroup
// operations and one shared entry per subgroup, one barrier, none where the
// workgroup is one subgroup (lavapipe pays for every barrier with a switch
// between the workgroup's threads). Distances are (dx*dx + dy*dy) + dz*dz in single
// precision with one rounding per operation (`precise`: no fma), as the
// PyTorch reference computes them, so the picks agree bit for bit.
// REGS: a thread's PER points (xyz and running minimum) live in registers
// (N <= L * PER); else the minimum lives in the workspace buffer and xyz is
// re-read each step (any N).
layout(local_size_x_id = 0) in;  // a power of two
layout(constant_id = 1) const uint PER = 4;  // >= 1
layout(constant_id = 2) const bool REGS = true;

layout(std430, binding = 0) readonly buffer Points_ { float pts[]; };  // [N, D], xyz = columns 0..2
layout(std430, binding = 1) writeonly buffer Index_ { int index[]; };  // [S]
layout(std430, binding = 2) writeonly buffer Centre_ { float centre[]; };  // [S, 3]
layout(std430, binding = 3) buffer Mind_ { float mind[]; };  // [N] workspace (PER == 0)
layout(push_constant) uniform Push { uint N; uint D; uint S; } p;

// Double-buffered by step parity, so a step needs no barrier after reading the result.
shared float red_d[2][gl_WorkGroupSize.x];
shared uint red_i[2][gl_WorkGroupSize.x];

float sqdist(vec3 a, vec3 c) {
    precise float dx = a.x - c.x;
    precise float dy = a.y - c.y;
    precise float dz = a.z - c.z;
    precise float d = (dx * dx + dy * dy) + dz * dz;
    return d;
}

vec3 point(uint i) { return vec3(pts[i * p.D], pts[i * p.D + 1u], pts[i * p.D + 2u]); }

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    vec3 own[PER];
    float md[PER];
    for (uint k = 0u; REGS && k < PER; ++k) {
        uint i = tid + k * L;
        own[k] = i < p.N ? point(i) : vec3(0.0);
        md[k] = uintBitsToFloat(0x7F800000u);  // +inf
    }
    uint far = 0u;
    for (uint step = 0u; step < p.S; ++step) {
        const vec3 c = point(far);
        if (tid == 0u) {
            index[step] = int(far);
            centre[3u * step] = c.x;
            centre[3u * step + 1u] = c.y;
            centre[3u * step + 2u] = c.z;
        }
        if (step + 1u == p.S) break;  // uniform: the last pick needs no search
        // Distances are >= 0, so -1 loses to any point; ascending i with a
        // strict > keeps the lowest index of a thread's ties.
        float best = -1.0;
        uint best_i = 0u;
        if (REGS) {
            for (uint k = 0u; k < PER; ++k) {
                uint i = tid + k * L;
                if (i < p.N) {
                    md[k] = min(md[k], sqdist(own[k], c));
                    if (md[k] > best) { best = md[k]; best_i = i; }
                }
            }
        } else {
            for (uint i = tid; i < p.N; i += L) {
                float d = sqdist(point(i), c);
                float m = step == 0u ? d : min(mind[i], d);
                mind[i] = m;
                if (m > best) { best = m; best_i = i; }
            }
        }
#ifdef SUBGROUP_REDUCE
        const uint b = step & 1u;
        const float sb = subgroupMax(best);
        const uint si = subgroupMin(best == sb ? best_i : 0xFFFFFFFFu);  // lowest index of the subgroup's ties
        if (gl_NumSubgroups == 1u) {  // uniform: the subgroup's winner is the step's, no barrier
            far = min(si, p.N - 1u);
            continue;
        }
        if (subgroupElect()) {
            red_d[b][gl_SubgroupID] = sb;
            red_i[b][gl_SubgroupID] = si;
        }
        barrier();
        // Lane l takes entries l, l + SG, ... (one each while L <= SG^2), then the
        // subgroup reduces them as above; every subgroup finds the same winner.
        float bd = uintBitsToFloat(0xFF800000u);  // -inf: no entry
        uint bi = 0xFFFFFFFFu;
        for (uint g = gl_SubgroupInvocationID; g < gl_NumSubgroups; g += gl_SubgroupSize) {
            const float od = red_d[b][g];
            const uint oi = red_i[b][g];
            if (od > bd || (od == bd && oi < bi)) { bd = od; bi = oi; }
        }
        const float wd = subgroupMax(bd);
        far = min(subgroupMin(bd == wd ? bi : 0xFFFFFFFFu), p.N - 1u);  // min: stays in bounds whatever NaNs did
#else
        const uint b = step & 1u;
        red_d[b][tid] = best;
        red_i[b][tid] = best_i;
        barrier();
        for (uint s = L >> 1u; s > 0u; s >>= 1u) {
            if (tid < s) {
                float od = red_d[b][tid + s];
                uint oi = red_i[b][tid + s];
                if (od > red_d[b][tid] || (od == red_d[b][tid] && oi < red_i[b][tid])) {
                    red_d[b][tid] = od;
                    red_i[b][tid] = oi;
                }
            }
            barrier();
        }
        far = min(red_i[b][0], p.N - 1u);  // min: stays in bounds whatever NaNs did
#endif
    }
}
