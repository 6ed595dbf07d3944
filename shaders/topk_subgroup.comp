#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_GOOGLE_include_directive : require
// topk.comp's selection (the same keys) for a small K in one subgroup per
// contact, without shared memory or barriers (topk_select.glsl). Only subgroup
// 0 works, so the result does not depend on how the driver splits the
// workgroup into subgroups.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint K = 5;

layout(std430, binding = 0) readonly buffer Contact_ { float contact[]; };
layout(binding = 1) uniform samplerBuffer tk_cand;  // [n, 3] as floats
layout(std430, binding = 2) writeonly buffer Index_ { int index[]; };
layout(std430, binding = 3) writeonly buffer Score_ { float score[]; };
layout(push_constant) uniform Push { uint n; } p;

#include "topk_select.glsl"

void main() {
    if (gl_SubgroupID != 0u) return;
    const uint row = gl_WorkGroupID.y;
    topk_scan(vec3(contact[3u * row], contact[3u * row + 1u], contact[3u * row + 2u]), p.n);
    for (uint r = 0u; r < K; ++r) {
        const uvec2 m = topk_pop();
        if (gl_SubgroupInvocationID == 0u) {
            index[row * K + r] = int(m.y);
            score[row * K + r] = uintBitsToFloat(m.x);
        }
    }
}
