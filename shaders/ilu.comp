#version 450
#extension GL_GOOGLE_include_directive : require
// The whole ILU in one dispatch (ilu_fused.glsl), row sums through shared memory.
#include "ilu_fused.glsl"
