#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
// Farthest point sampling with subgroup reductions, one barrier per step (see fps.glsl).
#define SUBGROUP_REDUCE
#include "fps.glsl"
