#version 450
#extension GL_GOOGLE_include_directive : require
// spin_marginal.glsl with prob in a storage buffer (past the device's texel limit).
layout(std430, binding = 0) readonly buffer In_ { float prob[]; };
#define LOAD_PROB(i) prob[i]
#include "spin_marginal.glsl"
