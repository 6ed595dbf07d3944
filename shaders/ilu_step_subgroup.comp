#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// One ILU iteration per dispatch (ilu_step_main.glsl), row sums by subgroup shuffles.
#define ILU_SUBGROUP 1
#include "ilu_step_main.glsl"
