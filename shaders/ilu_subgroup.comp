#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// The whole ILU in one dispatch (ilu_fused.glsl), row sums by subgroup shuffles.
#define ILU_SUBGROUP 1
#include "ilu_fused.glsl"
