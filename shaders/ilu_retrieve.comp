#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
// ilu_wave.comp with retrieve_subgroup.comp as its epilogue, one workgroup per
// touch: c_N is already in every lane's registers when the ILU ends, so
// subgroup 0 goes on to the top-K and heat-map of that touch. Why: on a CPU
// driver a dispatch and the barrier before it cost more than the retrieval
// itself (engine/ops/ilu_retrieve.cpp). No symmetry maps (KR = K); the
// workgroup is a whole number of subgroups, so subgroup 0 is full.
layout(local_size_x_id = 0) in;
layout(constant_id = 5) const uint K = 5;  // <= 16
const uint KR = K;
layout(push_constant) uniform Push { uint max_iters; uint P; uint D; uint M; uint K; uint T; } p;

#include "act.glsl"
#include "ilu_wave.glsl"

layout(binding = 15) uniform samplerBuffer cloud;                      // [P, D] as floats
layout(std430, binding = 16) readonly buffer Cand_ { float cand[]; };  // [M, 3]
layout(std430, binding = 17) buffer Index_ { int index[]; };           // [B, K], written here
layout(std430, binding = 18) readonly buffer Sym_ { float sym[]; };    // unused (no symmetry), any buffer
layout(std430, binding = 19) buffer Heat_ { float heat[]; };           // [B, P]
layout(binding = 20) uniform samplerBuffer tk_cand;                    // the candidates again, R32F
layout(std430, binding = 21) writeonly buffer Score_ { float score[]; };  // [B, K]
// 15-21: retrieve_subgroup.comp's 0-6 (retrieve.cpp's subgroup_bindings).

#include "topk_select.glsl"
#include "heatmap_row.glsl"

void main() {
    const vec3 c = ilu_wave_run();
    if (gl_SubgroupID != 0u) return;  // after the ILU's last barrier
    const uint row = gl_WorkGroupID.x;
    topk_scan(c, p.M);
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
