#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
// Body of expected_distance_subgroup.comp (points and weights as texel buffers) and
// expected_distance_subgroup_ssbo.comp (past the texel limit): bindings 0, 1, LOAD_P, LOAD_W.
// expected_distance.comp with the (point, weight) rows passed between lanes by
// subgroupShuffle instead of a shared-memory tile (why: chamfer_nn_subgroup.comp),
// Q answers a thread, each shuffled row serving Q distances. Zero weights are not
// skipped: w * d = 0 leaves the float sum as it was, so the sum is the tiled shader's,
// term for term in the same order. Every lane takes part in every shuffle (rows and
// answers past the end are zeros); the workgroup is whole subgroups (the host's choice).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint Q = 1;

layout(std430, binding = 2) readonly buffer A_ { float ans[]; };    // [A, 3]
layout(std430, binding = 3) writeonly buffer Out_ { float cost[]; };
layout(push_constant) uniform Push { uint S; uint A; } p;

void main() {
    const uint L = gl_WorkGroupSize.x, SG = gl_SubgroupSize;
    const uint j0 = gl_WorkGroupID.x * L * Q + gl_LocalInvocationID.x;
    vec3 pj[Q];
    float acc[Q];
    [[unroll]] for (uint k = 0u; k < Q; ++k) {
        const uint j = j0 + k * L;
        pj[k] = j < p.A ? vec3(ans[3u * j], ans[3u * j + 1u], ans[3u * j + 2u]) : vec3(0.0);
        acc[k] = 0.0;
    }
    for (uint s0 = 0u; s0 < p.S; s0 += SG) {
        const uint s = s0 + gl_SubgroupInvocationID;
        const vec4 row = s < p.S ? vec4(LOAD_P(3u * s), LOAD_P(3u * s + 1u), LOAD_P(3u * s + 2u), LOAD_W(s)) : vec4(0.0);
        const uint rows = min(SG, p.S - s0);
        for (uint i = 0u; i < rows; ++i) {
            const vec4 r = subgroupShuffle(row, i);
            [[unroll]] for (uint k = 0u; k < Q; ++k) {
                vec3 e = r.xyz - pj[k];
                acc[k] += r.w * sqrt((e.x * e.x + e.y * e.y) + e.z * e.z);
            }
        }
    }
    [[unroll]] for (uint k = 0u; k < Q; ++k) {
        const uint j = j0 + k * L;
        if (j < p.A) cost[j] = acc[k];
    }
}
