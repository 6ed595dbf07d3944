#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
// heatmap_score.comp and heatmap_norm.comp in one dispatch, one subgroup per row
// of a batch: each lane scores every S-th point (the same arithmetic as
// heatmap_score.comp), keeps its min and max, a butterfly of shuffles gives the
// row's, and each lane normalises the points it wrote (its own writes: no
// barrier needed). Why: on a CPU driver the two dispatches and the shared-memory
// tree cost several times the arithmetic of a 1024-point map. Only subgroup 0
// works, so the result does not depend on how the driver forms subgroups.
layout(local_size_x_id = 0) in;
// KR > 0 (no symmetry, K = KR <= 16): the K centres are loaded once, centre j by
// lane j % SG, and reach every lane by shuffles, instead of being re-read from
// memory for every point. SG = the subgroup size the host asked for.
layout(constant_id = 1) const uint KR = 0;
layout(constant_id = 2) const uint SG = 4;
const uint SLOTS = KR > 0u ? (KR + SG - 1u) / SG : 1u;

layout(binding = 0) uniform samplerBuffer cloud;                         // [P, D] as floats
layout(std430, binding = 1) readonly buffer Cand_ { float cand[]; };     // [M, 3]
layout(std430, binding = 2) readonly buffer Index_ { int index[]; };     // [B, K]
layout(std430, binding = 3) readonly buffer Sym_ { float sym[]; };       // [T, 12] when T > 0
layout(std430, binding = 4) buffer Heat_ { float heat[]; };              // [B, P]
layout(push_constant) uniform Push { uint P; uint D; uint M; uint K; uint T; } p;

void main() {
    if (gl_SubgroupID != 0u) return;
    const uint S = gl_SubgroupSize, lane = gl_SubgroupInvocationID, row = gl_WorkGroupID.y;
    vec2 m = vec2(1.0 / 0.0, -1.0 / 0.0);
    vec3 mine[SLOTS];
    if (KR > 0u)
        [[unroll]] for (uint s = 0u; s < SLOTS; ++s) {
            const uint j = s * SG + lane;
            const uint ci = j < KR ? min(uint(max(index[row * KR + j], 0)), p.M - 1u) : 0u;
            mine[s] = vec3(cand[ci * 3u], cand[ci * 3u + 1u], cand[ci * 3u + 2u]);
        }
    // Every lane runs every round (the shuffles need them all); a lane past the
    // end recomputes the last point and neither stores nor counts it.
    for (uint i0 = 0u; i0 < p.P; i0 += S) {
        const bool live = i0 + lane < p.P;
        const uint i = min(i0 + lane, p.P - 1u);
        vec3 pt = vec3(texelFetch(cloud, int(i * p.D)).x, texelFetch(cloud, int(i * p.D + 1u)).x,
                       texelFetch(cloud, int(i * p.D + 2u)).x);
        float best = 1.0 / 0.0;
        uint w = 1u;
        if (KR > 0u) {
            [[unroll]] for (uint j = 0u; j < KR; ++j) {
                const vec3 e = pt - subgroupShuffle(mine[j / SG], j % SG);
                const float d = sqrt((e.x * e.x + e.y * e.y) + e.z * e.z);
                if (d < best) {  // strict: an equal distance keeps the lower rank
                    best = d;
                    w = j + 1u;
                }
            }
        }
        for (uint j = 0u; j < (KR > 0u ? 0u : p.K); ++j) {
            uint ci = min(uint(max(index[row * p.K + j], 0)), p.M - 1u);  // never read outside the buffer
            vec3 c = vec3(cand[ci * 3u], cand[ci * 3u + 1u], cand[ci * 3u + 2u]);
            for (uint t = 0u; t < max(p.T, 1u); ++t) {
                vec3 ct = c;
                if (p.T > 0u) {
                    uint b = t * 12u;
                    ct = vec3(dot(vec3(sym[b], sym[b + 1u], sym[b + 2u]), c) + sym[b + 3u],
                              dot(vec3(sym[b + 4u], sym[b + 5u], sym[b + 6u]), c) + sym[b + 7u],
                              dot(vec3(sym[b + 8u], sym[b + 9u], sym[b + 10u]), c) + sym[b + 11u]);
                }
                vec3 e = pt - ct;
                float d = sqrt((e.x * e.x + e.y * e.y) + e.z * e.z);
                if (d < best) {  // strict: an equal distance keeps the lower rank
                    best = d;
                    w = j + 1u;
                }
            }
        }
        const float s = exp(-best) / float(w);
        if (live) {
            heat[row * p.P + i] = s;
            m = vec2(min(m.x, s), max(m.y, s));
        }
    }
    for (uint o = 1u; o < S; o <<= 1u) {
        const vec2 other = subgroupShuffleXor(m, o);
        m = vec2(min(m.x, other.x), max(m.y, other.y));
    }
    for (uint i = lane; i < p.P; i += S) {
        const uint at = row * p.P + i;
        heat[at] = m.y == m.x ? 0.0 : (heat[at] - m.x) / (m.y - m.x);
    }
}
