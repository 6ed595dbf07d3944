#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// topk.comp's selection (the same keys: (float bits of the score, index), ties
// to the lower index, NaN after every number) for a small K in one subgroup per
// contact, without shared memory or barriers: each lane scores every S-th
// candidate and keeps its K best keys sorted in registers; then K rounds each
// take the smallest head over the subgroup by a butterfly of shuffles and pop
// it from its lane. Why: topk.comp's bitonic sort reads shared memory at
// per-lane addresses behind log2(S)^2 / 2 barriers, which on a CPU driver costs
// far more than scanning a cloud. Only subgroup 0 works, so the result does not
// depend on how the driver splits the workgroup into subgroups.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint K = 5;

layout(std430, binding = 0) readonly buffer Contact_ { float contact[]; };
layout(binding = 1) uniform samplerBuffer cand;  // [n, 3] as floats
layout(std430, binding = 2) writeonly buffer Index_ { int index[]; };
layout(std430, binding = 3) writeonly buffer Score_ { float score[]; };
layout(push_constant) uniform Push { uint n; } p;

bool before(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

void main() {
    if (gl_SubgroupID != 0u) return;
    const uint S = gl_SubgroupSize, lane = gl_SubgroupInvocationID, row = gl_WorkGroupID.y;
    const vec3 c = vec3(contact[3u * row], contact[3u * row + 1u], contact[3u * row + 2u]);
    uvec2 best[K];
    for (uint j = 0u; j < K; ++j) best[j] = uvec2(0xFFFFFFFFu);
    for (uint i0 = 0u; i0 < p.n; i0 += S) {
        const uint i = i0 + lane;
        if (i >= p.n) break;
        // (dx*dx + dy*dy) + dz*dz, each operation rounded once, as the reference.
        precise float dx = texelFetch(cand, int(3u * i)).x - c.x;
        precise float dy = texelFetch(cand, int(3u * i + 1u)).x - c.y;
        precise float dz = texelFetch(cand, int(3u * i + 2u)).x - c.z;
        precise float s = (dx * dx + dy * dy) + dz * dz;
        uvec2 cur = uvec2(floatBitsToUint(s), i);
        for (uint j = 0u; j < K; ++j) {  // insertion into the sorted list, branch-free
            const bool lt = before(cur, best[j]);
            const uvec2 t = best[j];
            best[j] = lt ? cur : t;
            cur = lt ? t : cur;
        }
    }
    for (uint r = 0u; r < K; ++r) {
        uvec2 m = best[0];
        for (uint o = 1u; o < S; o <<= 1u) {
            const uvec2 other = subgroupShuffleXor(m, o);
            m = before(other, m) ? other : m;
        }
        if (lane == 0u) {
            index[row * K + r] = int(m.y);
            score[row * K + r] = uintBitsToFloat(m.x);
        }
        if (best[0] == m) {  // the one lane holding it (keys are unique: they carry the index)
            for (uint j = 0u; j + 1u < K; ++j) best[j] = best[j + 1u];
            best[K - 1u] = uvec2(0xFFFFFFFFu);
        }
    }
}
