#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// topk_subgroup.comp and heatmap_subgroup.comp in one dispatch, one subgroup
// per contact: the K best candidates come out of the butterfly in every lane,
// so they are the heat-map's centres as they are, without a store, a barrier or
// a second dispatch. No symmetry maps (KR = K); only subgroup 0 works.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint K = 5;   // <= 16
const uint KR = K;

layout(binding = 0) uniform samplerBuffer cloud;                     // [P, D] as floats
layout(std430, binding = 1) readonly buffer Cand_ { float cand[]; }; // [M, 3]
layout(std430, binding = 2) buffer Index_ { int index[]; };          // [B, K], written here
layout(std430, binding = 3) readonly buffer Sym_ { float sym[]; };   // unused (no symmetry), any buffer
layout(std430, binding = 4) buffer Heat_ { float heat[]; };          // [B, P]
layout(binding = 5) uniform samplerBuffer tk_cand;                   // the candidates again, R32F
layout(std430, binding = 6) writeonly buffer Score_ { float score[]; };    // [B, K]
// Bindings 0-6 are ilu_retrieve.comp's 15-21 (retrieve.cpp's subgroup_bindings).
layout(std430, binding = 7) readonly buffer Contact_ { float contact[]; };  // [B, 3]
layout(push_constant) uniform Push { uint P; uint D; uint M; uint K; uint T; } p;

#include "topk_select.glsl"
#include "heatmap_row.glsl"

void main() {
    if (gl_SubgroupID != 0u) return;
    const uint row = gl_WorkGroupID.y;
    topk_scan(vec3(contact[3u * row], contact[3u * row + 1u], contact[3u * row + 2u]), p.M);
    [[unroll]] for (uint r = 0u; r < K; ++r) {
        const uvec2 m = topk_pop();
        if (gl_SubgroupInvocationID == 0u) {
            index[row * K + r] = int(m.y);
            score[row * K + r] = uintBitsToFloat(m.x);
        }
        hm_set_centre(r, m.y);
    }
    heat_row(row);
}
