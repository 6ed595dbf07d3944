#version 450
#extension GL_GOOGLE_include_directive : require
// codebook_score.glsl with its inputs in storage buffers (past the device's texel limit).
layout(std430, binding = 0) readonly buffer Quads_ { vec4 quads[]; }; // [S, (G+1)^2] (make_quads)
layout(std430, binding = 1) readonly buffer Spins_ { float spins[]; }; // [NS, 2]
layout(std430, binding = 3) readonly buffer Wmin_ { float wmins[]; };  // [S * NS] (codebook_window_min)
#define LOAD_QUAD(i) quads[i]
#define LOAD_SPIN(i) spins[i]
#define LOAD_WMIN(i) wmins[i]
#include "codebook_score.glsl"
