#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_KHR_shader_subgroup_vote : require
// point_mlp.comp with the weights as a texel buffer (binding 2), each weight row
// loaded once per subgroup: lane l reads columns l, l + SG, ... (or, where N % 4
// == 0, the vec4s of columns 4l .. 4l + 3, ...) and the lanes share them by
// shuffles at constant lane indices (a register permute on a CPU driver), where
// every lane reading every weight was a gather per weight.
#include "point_mlp_texel.glsl"
layout(binding = 2) uniform samplerBuffer WT;  // R32F, or RGBA32F where N % 4 == 0 (WVEC4)
#define LOAD_W(e) texelFetch(WT, int(e)).x
#define LOAD_WV4(e) texelFetch(WT, int(e))
#define WEIGHTS_SHUFFLE
#define SUBGROUP_VOTE  // PAD skips whole blocks
#include "point_mlp.glsl"
