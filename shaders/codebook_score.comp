#version 450
#extension GL_GOOGLE_include_directive : require
// codebook_score.glsl with the quads, spins and window minima read through uniform texel
// buffers: gathers on a CPU driver, where storage reads at each lane's own offset are
// loops over the lanes that stall on store forwarding with AVX2 only (docs/render_compare.md,
// "Speed").
layout(binding = 0) uniform samplerBuffer Quads;  // RGBA32F, [S, (G+1)^2] (make_quads)
layout(binding = 1) uniform samplerBuffer Spins;  // R32F, [NS, 2]
layout(binding = 3) uniform samplerBuffer Wmins;  // R32F, [S * NS] (codebook_window_min)
#define LOAD_QUAD(i) texelFetch(Quads, int(i))
#define LOAD_SPIN(i) texelFetch(Spins, int(i)).x
#define LOAD_WMIN(i) texelFetch(Wmins, int(i)).x
#include "codebook_score.glsl"
