#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// expected_distance_subgroup.glsl with the points and weights read through uniform texel
// buffers (R32F): gathers on a CPU driver, where storage reads at each lane's own offset
// are loops over the lanes (docs/multitouch.md, "The tables as texels").
layout(binding = 0) uniform samplerBuffer Pts;  // [S, 3]
layout(binding = 1) uniform samplerBuffer W;    // [S]
#define LOAD_P(i) texelFetch(Pts, int(i)).x
#define LOAD_W(i) texelFetch(W, int(i)).x
#include "expected_distance_subgroup.glsl"
