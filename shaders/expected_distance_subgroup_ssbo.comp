#version 450
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// expected_distance_subgroup.glsl with the points and weights in storage buffers (past the
// device's texel limit).
layout(std430, binding = 0) readonly buffer Pts_ { float pts[]; };  // [S, 3]
layout(std430, binding = 1) readonly buffer W_ { float w[]; };      // [S]
#define LOAD_P(i) pts[i]
#define LOAD_W(i) w[i]
#include "expected_distance_subgroup.glsl"
