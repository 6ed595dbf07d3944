#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// max_pool2d reading its input as a uniform texel buffer (a gather on CPU devices).
layout(binding = 0) uniform samplerBuffer X;  // R32F
#define LOAD_X(i) texelFetch(X, i).x
#include "max_pool2d.glsl"
