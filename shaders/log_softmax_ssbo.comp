#version 450
#extension GL_GOOGLE_include_directive : require
// log_softmax.glsl with the score in a storage buffer (past the device's texel limit).
layout(std430, binding = 0) readonly buffer In_ { float v[]; };
#define LOAD_V(i) v[i]
#include "log_softmax.glsl"
