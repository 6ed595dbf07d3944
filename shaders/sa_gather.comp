#version 450
#extension GL_GOOGLE_include_directive : require
// sa_gather.glsl with U read through a uniform texel buffer (a gather on CPU devices).
layout(binding = 0) uniform samplerBuffer Ut;  // R32F
#define LOAD_U(i) texelFetch(Ut, int(i)).x
#include "sa_gather.glsl"
