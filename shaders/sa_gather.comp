#version 450
#extension GL_GOOGLE_include_directive : require
// sa_gather.glsl with U and W read through uniform texel buffers: a gather on CPU
// devices, where a storage-buffer load at an address Mesa cannot prove uniform (the
// weights' is uniform, but moves with the loop) is a loop over the lanes.
layout(binding = 0) uniform samplerBuffer Ut;  // R32F
layout(binding = 3) uniform samplerBuffer Wt;  // R32F, [K, N]
#define LOAD_U(i) texelFetch(Ut, int(i)).x
#define LOAD_W(i) texelFetch(Wt, int(i)).x
#include "sa_gather.glsl"
