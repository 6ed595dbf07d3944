#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// max_pool2d reading a storage buffer: the fallback past maxTexelBufferElements.
layout(std430, binding = 0) readonly buffer X_ { float X[]; };
#define LOAD_X(i) X[i]
#include "max_pool2d.glsl"
