#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// The whole ILU (SPEC 2) in one dispatch: shaders/ilu_wave.glsl, which says why.
layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { uint max_iters; } p;
#include "act.glsl"
#include "ilu_wave.glsl"

void main() { ilu_wave_run(); }
