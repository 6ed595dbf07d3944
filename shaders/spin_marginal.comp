#version 450
#extension GL_GOOGLE_include_directive : require
// spin_marginal.glsl with prob read through a uniform texel buffer (R32F): a gather on a
// CPU driver, where a storage read at each lane's own offset is a loop over the lanes
// (stalling on store forwarding with AVX2 only: docs/multitouch.md, "The tables as texels").
layout(binding = 0) uniform samplerBuffer Prob;
#define LOAD_PROB(i) texelFetch(Prob, int(i)).x
#include "spin_marginal.glsl"
