#version 450
#extension GL_GOOGLE_include_directive : require
// log_softmax.glsl with the score read through a uniform texel buffer (R32F): a gather
// on a CPU driver, where a storage read at each lane's own offset is a loop over the
// lanes (with AVX2 only, each insert stalls on store forwarding).
layout(binding = 0) uniform samplerBuffer V;
#define LOAD_V(i) texelFetch(V, int(i)).x
#include "log_softmax.glsl"
