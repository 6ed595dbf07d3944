#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// heatmap_score.comp and heatmap_norm.comp in one dispatch, one subgroup per row
// of a batch (heatmap_row.glsl, the same arithmetic as heatmap_score.comp).
// Why: on a CPU driver the two dispatches and the shared-memory tree cost
// several times the arithmetic of a 1024-point map. Only subgroup 0 works, so
// the result does not depend on how the driver forms subgroups.
layout(local_size_x_id = 0) in;
// KR > 0 (no symmetry, K = KR <= 16): the K centres are loaded once into every
// lane (heatmap_row.glsl); else they are read per point, with the symmetry maps.
layout(constant_id = 1) const uint KR = 0;

layout(binding = 0) uniform samplerBuffer cloud;                         // [P, D] as floats
layout(std430, binding = 1) readonly buffer Cand_ { float cand[]; };     // [M, 3]
layout(std430, binding = 2) readonly buffer Index_ { int index[]; };     // [B, K]
layout(std430, binding = 3) readonly buffer Sym_ { float sym[]; };       // [T, 12] when T > 0
layout(std430, binding = 4) buffer Heat_ { float heat[]; };              // [B, P]
layout(push_constant) uniform Push { uint P; uint D; uint M; uint K; uint T; } p;

#include "heatmap_row.glsl"

void main() {
    if (gl_SubgroupID != 0u) return;
    const uint row = gl_WorkGroupID.y;
    if (KR > 0u)
        [[unroll]] for (uint j = 0u; j < KR; ++j) hm_set_centre(j, uint(max(index[row * KR + j], 0)));
    heat_row(row);
}
