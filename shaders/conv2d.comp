#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// conv2d reading its inputs through uniform texel buffers: on lavapipe a texel
// fetch is a branch-free gather, a storage-buffer load a loop over the lanes, so
// this runs ~2x faster and compiles ~3x faster than conv2d_ssbo.comp.
layout(binding = 0) uniform samplerBuffer X;     // R32F
layout(binding = 1) uniform samplerBuffer Wt;    // R32F
layout(binding = 2) uniform samplerBuffer Wt4;   // the weights again, RGBA32F
layout(binding = 3) uniform samplerBuffer Bias;  // R32F
layout(binding = 4) uniform samplerBuffer Res;   // R32F
layout(binding = 6) uniform samplerBuffer X4;    // x again, RGBA32F
layout(binding = 8) uniform samplerBuffer Res4;  // the residual again, RGBA32F
#define LOAD_X(i) texelFetch(X, i).x
#define LOAD_W(i) texelFetch(Wt, i).x
#define LOAD_W4(i) texelFetch(Wt4, i)
#define LOAD_BIAS(i) texelFetch(Bias, i).x
#define LOAD_RES(i) texelFetch(Res, i).x
#define LOAD_X4(i) texelFetch(X4, i)
#define LOAD_RES4(i) texelFetch(Res4, i)
#include "conv2d.glsl"
