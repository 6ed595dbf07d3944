#version 450
#extension GL_GOOGLE_include_directive : require
// sa_gather.glsl with U in a storage buffer (beyond the device's texel-buffer limit).
layout(std430, binding = 0) readonly buffer U_ { float U[]; };  // [N, P]
layout(std430, binding = 3) readonly buffer W_ { float W[]; };  // [K, N]
#define LOAD_U(i) U[i]
#define LOAD_W(i) W[i]
#include "sa_gather.glsl"
